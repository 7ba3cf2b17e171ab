package confront;

/**
 * The fixed gun/radar controller of the exported robots (confront.arena.control.aim, smdp.controller_turn) and
 * the angle helpers it and the models use (no Robocode dependency). Angles follow Robocode: radians, 0 = north
 * (+y), clockwise; enemy rows start with {x, y, ...}.
 */
public final class Aim {
    static final double TWO_PI = 2 * Math.PI;
    final double overshoot;
    final double tolerance;
    final double powerNear;
    final double powerMid;
    final double powerFar;
    final double nearDistance;
    final double farDistance;
    final boolean fire;

    /** The controller's settings from a model file (the keys of confront.arena.control.ControlConfig). */
    Aim(ModelFile f) {
        overshoot = f.num("radar_overshoot");
        tolerance = f.num("aim_tolerance");
        powerNear = f.num("power_near");
        powerMid = f.num("power_mid");
        powerFar = f.num("power_far");
        nearDistance = f.num("near_distance");
        farDistance = f.num("far_distance");
        fire = f.num("fire") != 0;
    }

    /** (gun turn, radar turn, fire power) with no target: keep the gun (NaN), a full radar turn, no fire. */
    static double[] none() {
        return new double[] {Double.NaN, TWO_PI, 0.0};
    }

    /**
     * (gun turn, radar turn, fire power) toward (tx, ty): the gun and the radar turned to its bearing, the radar
     * past it by the overshoot (keeps the lock); fire with the gun within the tolerance, cold, and energy left, at
     * {@code power} (> 0), hold (< 0), or by distance band (0).
     */
    double[] toward(double x, double y, double tx, double ty, double gunHeading, double radarHeading, double gunHeat,
                    double energy, double power) {
        return toward(x, y, tx, ty, Math.atan2(tx - x, ty - y), gunHeading, radarHeading, gunHeat, energy, power);
    }

    /** toward() with the gun turned to the absolute angle gunBearing (smdp_kernel.controller_aim). */
    double[] toward(double x, double y, double tx, double ty, double gunBearing, double gunHeading,
                    double radarHeading, double gunHeat, double energy, double power) {
        double dx = tx - x;
        double dy = ty - y;
        double bearing = Math.atan2(dx, dy);
        double dist = Math.hypot(dx, dy);
        double gun = relAngle(gunBearing - gunHeading);
        double radar = relAngle(bearing - radarHeading);
        radar = radar + Math.signum(radar) * overshoot;
        boolean shoot = Math.abs(gun) <= tolerance && gunHeat == 0 && energy > 0 && fire;
        double p;
        if (!shoot || power < 0) {
            p = 0.0;
        } else if (power > 0) {
            p = power;
        } else if (dist < nearDistance) {
            p = powerNear;
        } else if (dist < farDistance) {
            p = powerMid;
        } else {
            p = powerFar;
        }
        return new double[] {gun, radar, p};
    }

    /** Angle in [0, 2pi) (Robocode Utils.normalAbsoluteAngle). */
    static double absAngle(double a) {
        double r = a - TWO_PI * Math.floor(a / TWO_PI);
        return r >= TWO_PI ? 0.0 : r;
    }

    /** Angle wrapped to [-pi, pi) as (a + pi) mod 2 pi - pi (numpy's float mod, observe.float_mod). */
    static double relAngle(double a) {
        double s = a + Math.PI;
        double r = s % TWO_PI;  // fmod
        if (r < 0) {
            r += TWO_PI;
        }
        return r - Math.PI;
    }

    /** The row of the nearest enemy by squared distance (first of equals), -1 if none. */
    static int nearest(double x, double y, double[][] enemies) {
        int best = -1;
        double bestD = Double.POSITIVE_INFINITY;
        for (int j = 0; j < enemies.length; j++) {
            double dx = enemies[j][0] - x;
            double dy = enemies[j][1] - y;
            double d = dx * dx + dy * dy;
            if (d < bestD) {
                best = j;
                bestD = d;
            }
        }
        return best;
    }
}
