package confront;

/** Helper for robots at round start. */
public final class RoundStart {
    private RoundStart() {
    }

    /**
     * The engine starts a robot, then waits on a monitor for its first execute(); if that execute() comes
     * before the engine is waiting, the wake-up is lost and the engine waits its full time-out (up to 10 s)
     * [RobotPeer.startRound]. Pausing 3 ms before the first action lets the engine be waiting. The runner's
     * RoundStartAgent removes the lost wake-up for every robot; this pause only matters without it.
     */
    public static void awaitEngine() {
        try {
            Thread.sleep(3);
        } catch (InterruptedException e) {
            Thread.currentThread().interrupt();
        }
    }
}
