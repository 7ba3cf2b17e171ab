package confront;

import java.io.IOException;
import java.io.InputStream;
import java.io.InputStreamReader;
import java.io.Reader;
import java.io.StringReader;
import java.nio.charset.StandardCharsets;

import robocode.AdvancedRobot;

/** The pieces confront's robots share on the Robocode side: round start, model text, gun/radar commands. */
public final class RobotParts {
    private RobotParts() {
    }

    /** Gun, radar and body turn independently; then the pause for the engine's round start (RoundStart). */
    static void start(AdvancedRobot r) {
        r.setAdjustGunForRobotTurn(true);
        r.setAdjustRadarForRobotTurn(true);
        r.setAdjustRadarForGunTurn(true);
        RoundStart.awaitEngine();
    }

    /** A robot whose model did not load: says why ("CONFRONT <tag> <error>") and spins its radar for good. */
    static void idle(AdvancedRobot r, String tag, Exception e) {
        r.out.println("CONFRONT " + tag + " " + e);
        while (true) {
            r.setTurnRadarRightRadians(2 * Math.PI);
            r.execute();
        }
    }

    /**
     * The model text compiled into the class confront.{@code data} (its CHUNKS, written at export: no file access,
     * in the sandbox or from a jar), else the resource {@code file} beside the robot's class.
     */
    static Reader embedded(AdvancedRobot r, String data, String file) throws IOException {
        try {
            String[] chunks = (String[]) Class.forName("confront." + data).getField("CHUNKS").get(null);
            return new StringReader(String.join("", chunks));
        } catch (ReflectiveOperationException e) {
            InputStream res = r.getClass().getResourceAsStream(file);
            if (res == null) {
                throw new IOException("no confront." + data + " class and no " + file);
            }
            return new InputStreamReader(res, StandardCharsets.UTF_8);
        }
    }

    /** Sets the controller's (gun turn, radar turn, fire power): gun NaN keeps the gun, power 0 holds; true if
     *  it fires. */
    static boolean command(AdvancedRobot r, double[] g) {
        if (!Double.isNaN(g[0])) {
            r.setTurnGunRightRadians(g[0]);
        }
        r.setTurnRadarRightRadians(g[1]);
        if (g[2] > 0) {
            r.setFire(g[2]);
            return true;
        }
        return false;
    }
}
