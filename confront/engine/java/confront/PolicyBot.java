package confront;

import java.io.IOException;
import java.io.InputStream;
import java.io.InputStreamReader;
import java.io.Reader;
import java.io.StringReader;
import java.nio.charset.StandardCharsets;
import java.util.HashSet;
import java.util.LinkedHashMap;
import java.util.Map;
import java.util.Set;

import robocode.MessageEvent;
import robocode.RobotDeathEvent;
import robocode.ScannedRobotEvent;
import robocode.TeamRobot;

/**
 * A trained policy exported from confront, running with no Python: reads its policy (compiled into
 * confront.PolicyData at export, so no file access is needed in the sandbox or from a jar), picks one of the paper's four moves every step_turns turns from the latest
 * scans of enemies (team-mates are ignored), and runs the fixed gun/radar controller every turn.
 */
public class PolicyBot extends TeamRobot {
    private final Map<String, double[]> enemies = new LinkedHashMap<>();
    /** Names that sent us a message: team-mates. Robocode 1.9.3.9's own list misses the mates of a team that is
     *  not first in the battle (its members carry a per-class count, the robots their battle index), so every
     *  PolicyBot announces itself in its first turn. */
    private final Set<String> heard = new HashSet<>();

    @Override
    public void run() {
        setAdjustGunForRobotTurn(true);
        setAdjustRadarForRobotTurn(true);
        setAdjustRadarForGunTurn(true);
        RoundStart.awaitEngine();
        PolicyModel model;
        try {
            model = load();
        } catch (IOException | RuntimeException e) {
            out.println("CONFRONT policy-load-failed " + e);
            while (true) {
                setTurnRadarRightRadians(2 * Math.PI);
                execute();
            }
        }
        int step = model.stepTurns();
        if (getTeammates() != null) {
            try {
                broadcastMessage(Boolean.TRUE);
            } catch (IOException e) {
                out.println("CONFRONT policy-error broadcast " + e);
            }
        }
        while (true) {
            double[][] e = known();
            long turn = getTime() + 1;  // the commands set now take effect in this turn
            if ((turn - 1) % step == 0) {
                int a = model.act(getX(), getY(), getHeadingRadians(), getEnergy(), e[0], e[1], e[2],
                        getBattleFieldWidth(), getBattleFieldHeight());
                double[] mv = model.move(a);
                setAhead(mv[0]);
                setTurnRightRadians(mv[1]);
            }
            double[] g = model.gunRadar(getX(), getY(), getGunHeadingRadians(), getRadarHeadingRadians(),
                    getGunHeat(), getEnergy(), e[0], e[1]);
            if (!Double.isNaN(g[0])) {
                setTurnGunRightRadians(g[0]);
            }
            setTurnRadarRightRadians(g[1]);
            if (g[2] > 0) {
                setFire(g[2]);
            }
            execute();
        }
    }

    /** The policy compiled into confront.PolicyData (written at export), else policy.txt beside the class. */
    private PolicyModel load() throws IOException {
        try {
            String[] chunks = (String[]) Class.forName("confront.PolicyData").getField("CHUNKS").get(null);
            return PolicyModel.read(new StringReader(String.join("", chunks)));
        } catch (ReflectiveOperationException e) {
            InputStream res = getClass().getResourceAsStream("policy.txt");
            if (res == null) {
                throw new IOException("no confront.PolicyData class and no policy.txt");
            }
            try (Reader r = new InputStreamReader(res, StandardCharsets.UTF_8)) {
                return PolicyModel.read(r);
            }
        }
    }

    private double[][] known() {
        int n = enemies.size();
        double[][] e = new double[3][n];
        int i = 0;
        for (double[] v : enemies.values()) {
            e[0][i] = v[0];
            e[1][i] = v[1];
            e[2][i] = v[2];
            i++;
        }
        return e;
    }

    @Override
    public void onScannedRobot(ScannedRobotEvent e) {
        if (isTeammate(e.getName()) || heard.contains(e.getName())) {
            return;
        }
        double abs = getHeadingRadians() + e.getBearingRadians();
        enemies.put(e.getName(), new double[] {getX() + e.getDistance() * Math.sin(abs),
                getY() + e.getDistance() * Math.cos(abs), e.getEnergy()});
    }

    @Override
    public void onMessageReceived(MessageEvent e) {
        if (e.getSender() != null) {
            heard.add(e.getSender());
            enemies.remove(e.getSender());  // scanned before its message arrived
        }
    }

    @Override
    public void onRobotDeath(RobotDeathEvent e) {
        enemies.remove(e.getName());
    }
}
