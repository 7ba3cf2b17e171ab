"""Java's ``StrictMath.sin`` / ``StrictMath.cos`` bit for bit (fdlibm 5.3: s_sin, s_cos, k_sin, k_cos, e_rem_pio2).

The technique robots (:mod:`confront.arena.tech`) predict paths with many sines and cosines; ``Math.sin`` (a HotSpot
intrinsic) and the C library differ by an ulp in about 0.2 % of calls, enough to flip a decision now and then, so the
Java robots call ``StrictMath`` and the simulator computes the same fdlibm arithmetic here. Arguments up to
2^19 * pi / 2 in magnitude (fdlibm's medium reduction); larger ones fall back to the C library.
"""

from __future__ import annotations

import math

from numba import njit

from .kernel_cache import install
from .rules import float_bits, float_from_bits

__all__ = ["strict_sin", "strict_cos"]

_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11
_INVPIO2 = 6.36619772367581382433e-01
_PIO2_1, _PIO2_1T = 1.57079632673412561417e+00, 6.07710050650619224932e-11
_PIO2_2, _PIO2_2T = 6.07710050630396597660e-11, 2.02226624879595063154e-21
_PIO2_3, _PIO2_3T = 2.02226624871116645580e-21, 8.47842766036889956997e-32
_NPIO2_HW = (
    0x3FF921FB, 0x400921FB, 0x4012D97C, 0x401921FB, 0x401F6A7A, 0x4022D97C, 0x4025FDBB, 0x402921FB, 0x402C463A,
    0x402F6A7A, 0x4031475C, 0x4032D97C, 0x40346B9C, 0x4035FDBB, 0x40378FDB, 0x403921FB, 0x403AB41B, 0x403C463A,
    0x403DD85A, 0x403F6A7A, 0x40407E4C, 0x4041475C, 0x4042106C, 0x4042D97C, 0x4043A28C, 0x40446B9C, 0x404534AC,
    0x4045FDBB, 0x4046C6CB, 0x40478FDB, 0x404858EB, 0x404921FB,
)


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _hi(x):
    """fdlibm's __HI: the upper 32 bits as a signed int."""
    h = (float_bits(x) >> 32) & 0xFFFFFFFF
    return h - (1 << 32) if h >= (1 << 31) else h


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _k_sin(x, y, iy):
    """__kernel_sin on [-pi/4, pi/4]; y the tail of x, iy = 0 when y is zero."""
    ix = _hi(x) & 0x7FFFFFFF
    if ix < 0x3E400000 and int(x) == 0:
        return x
    z = x * x
    v = z * x
    r = _S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))
    if iy == 0:
        return x + v * (_S1 + z * r)
    return x - ((z * (0.5 * y - v * r) - y) - v * _S1)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _k_cos(x, y):
    """__kernel_cos on [-pi/4, pi/4]."""
    ix = _hi(x) & 0x7FFFFFFF
    if ix < 0x3E400000 and int(x) == 0:
        return 1.0
    z = x * x
    r = z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    if ix < 0x3FD33333:
        return 1.0 - (0.5 * z - (z * r - x * y))
    if ix > 0x3FE90000:
        qx = 0.28125
    else:
        qx = float_from_bits((ix - 0x00200000) << 32)  # x/4: high word ix - 2^21, low word 0
    hz = 0.5 * z - qx
    a = 1.0 - qx
    return a - (hz - (z * r - x * y))


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _rem_pio2(x):
    """__ieee754_rem_pio2 for |x| <= 2^19 pi/2: (n, y0, y1) with x = n pi/2 + y0 + y1."""
    hx = _hi(x)
    ix = hx & 0x7FFFFFFF
    if ix <= 0x3FE921FB:
        return 0, x, 0.0
    if ix < 0x4002D97C:
        if hx > 0:
            z = x - _PIO2_1
            if ix != 0x3FF921FB:
                y0 = z - _PIO2_1T
                return 1, y0, (z - y0) - _PIO2_1T
            z -= _PIO2_2
            y0 = z - _PIO2_2T
            return 1, y0, (z - y0) - _PIO2_2T
        z = x + _PIO2_1
        if ix != 0x3FF921FB:
            y0 = z + _PIO2_1T
            return -1, y0, (z - y0) + _PIO2_1T
        z += _PIO2_2
        y0 = z + _PIO2_2T
        return -1, y0, (z - y0) + _PIO2_2T
    t = abs(x)
    n = int(t * _INVPIO2 + 0.5)
    fn = float(n)
    r = t - fn * _PIO2_1
    w = fn * _PIO2_1T
    if n < 32 and ix != _NPIO2_HW[n - 1]:
        y0 = r - w
    else:
        j = ix >> 20
        y0 = r - w
        i = j - ((_hi(y0) >> 20) & 0x7FF)
        if i > 16:
            t = r
            w = fn * _PIO2_2
            r = t - w
            w = fn * _PIO2_2T - ((t - r) - w)
            y0 = r - w
            i = j - ((_hi(y0) >> 20) & 0x7FF)
            if i > 49:
                t = r
                w = fn * _PIO2_3
                r = t - w
                w = fn * _PIO2_3T - ((t - r) - w)
                y0 = r - w
    y1 = (r - y0) - w
    if hx < 0:
        return -n, -y0, -y1
    return n, y0, y1


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def strict_sin(x: float) -> float:
    """StrictMath.sin(x) (fdlibm s_sin)."""
    ix = _hi(x) & 0x7FFFFFFF
    if ix <= 0x3FE921FB:
        return _k_sin(x, 0.0, 0)
    if ix >= 0x7FF00000:
        return x - x
    if ix > 0x413921FB:
        return math.sin(x)
    n, y0, y1 = _rem_pio2(x)
    q = n & 3
    if q == 0:
        return _k_sin(y0, y1, 1)
    if q == 1:
        return _k_cos(y0, y1)
    if q == 2:
        return -_k_sin(y0, y1, 1)
    return -_k_cos(y0, y1)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def strict_cos(x: float) -> float:
    """StrictMath.cos(x) (fdlibm s_cos)."""
    ix = _hi(x) & 0x7FFFFFFF
    if ix <= 0x3FE921FB:
        return _k_cos(x, 0.0)
    if ix >= 0x7FF00000:
        return x - x
    if ix > 0x413921FB:
        return math.cos(x)
    n, y0, y1 = _rem_pio2(x)
    q = n & 3
    if q == 0:
        return _k_cos(y0, y1)
    if q == 1:
        return -_k_sin(y0, y1, 1)
    if q == 2:
        return -_k_cos(y0, y1)
    return _k_sin(y0, y1, 1)


install(globals())
