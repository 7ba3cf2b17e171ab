"""Scripted robots that behave like Robocode's sample robots, compiled and batched: one module per robot.

SittingDuck, SpinBot, Walls, Tracker, RamFire, Fire, Corners, Crazy, TrackFire and the sample team
MyFirstTeam (MyFirstLeader, MyFirstDroid), written from their observable behaviour (main loop of blocking
calls, event handlers). The package:

- ``common.py``: what a robot's module uses: ``Robot`` (its description), ``Event`` (what it acts on),
  ``Scene`` (what it sees), the operation codes ``O_*``, the memory layout ``M_*``, ``run_op`` /
  ``handler_op`` (queue an operation in run() / in the running handler), angle helpers in Robocode's degrees.
- ``controller.py``: Robocode's event manager and blocking calls, turn by turn (event queue, execution
  levels, operations; ``bots_step``, ``play_range``).
- ``registry.py``: the robots by kind (``ROBOTS``) and the compiled dispatch ``act(kind, ...)``.
- ``scripted.py``: the Python side: ``ScriptedBots(arena, names)``, ``bot_battle(names, rounds)``.
- one module per robot (``spinbot.py``, ``walls.py``, ..., ``myfirstteam.py``).

Usage: ``bots = ScriptedBots(arena, ["SpinBot", None, ...])`` (a name per robot, None = driven by
someone else), then every turn ``bots.commands(cmd)`` fills those robots' rows of ``cmd``. A new
round (``state.round`` changed) clears the memory of that battle's bots by itself.

Adding a robot (say ``MyBot``):

1. Write ``bots/mybot.py`` after ``spinbot.py``: ``KIND`` (the next free code), ``ROBOT = Robot("MyBot", KIND,
   advanced=..., memory=...)`` and ``@njit(**KERNEL_INLINE) def act(kind, mem, b, i, ev, s)``, which returns at
   once unless ``kind == KIND``, then runs the robot's code by ``ev.prio`` (constants of ``common``, imported
   as ``c``): ``c.P_RUN`` queues the next pass of ``run()`` with ``run_op(mem, b, i, c.O_..., value)``
   (``ev.aux`` is 1.0 in the round's first pass: its set-up part); ``c.P_SCAN``, ``c.P_BULLET``, ``c.P_WALL``,
   ``c.P_ROBOT``, ``c.P_MESSAGE``, ``c.P_WIN`` are its ``onXxx`` handlers, which queue with ``handler_op``;
   ``c.P_DEATH`` is ``onDeath``; ``c.P_MARK`` runs a bookkeeping step it queued as ``c.O_SETMAXV`` with a
   negative code (in ``ev.aux``). The event's data are in ``ev`` (``bearing`` in radians, ``dist``, ``energy``,
   the other robot ``j``), the arena's robots in ``s.robots`` (``s.robots.f[b, kernels.X, i]`` ...), the
   commands in ``s.cmd``. End the module with ``install(globals())`` (the kernel cache).
2. Register it in ``registry.py``: import the module, add its ``ROBOT`` to ``ROBOTS`` and one line to ``act``:
   ``mybot.act(kind, mem, b, i, ev, s)`` (in the branch of its kind: ``act`` calls a few robots per branch).

Its state is its memory row ``mem[b, i]`` (float64): the variables ``c.M_VAR .. c.M_VAR + 7`` are cleared at each
new round (``run()``'s fields); its own ``ROBOT.memory`` floats at ``c.M_OWN ..`` are kept across the rounds of a
battle, as ``c.M_STATIC`` (Corners' corner) is: its per-battle memory (GuessFactor bins, waves, per-robot
arrays: give each its offset as a module constant, ``c.M_OWN + k``; ``ScriptedBots`` sizes the rows for the
largest ``memory`` of its robots). Clear what must start afresh each round at the round's first ``c.P_RUN``.
Then run ``python scripts/build_kernels.py`` (the shipped kernels) and add the robot to the tests
(``tests/arena/test_bots.py``; against recorded engine traces in ``test_bots_engine.py``).
"""

from .common import Robot
from .controller import BotState, bots_step, play_range
from .registry import ROBOTS
from .scripted import ADVANCED_BOTS, BOT_NAMES, ScriptedBots, bot_battle, bot_kind, teammate_masks

__all__ = ["BOT_NAMES", "ADVANCED_BOTS", "ROBOTS", "Robot", "BotState", "ScriptedBots", "bot_kind", "bot_battle",
           "bots_step", "play_range", "teammate_masks"]
