package confront;

import java.io.IOException;
import java.io.Reader;
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
 * confront.PolicyData at export, so no file access is needed in the sandbox or from a jar; else policy.txt beside
 * the class), picks one of the paper's four moves every step_turns turns from the latest scans of enemies
 * (team-mates are ignored), and runs the fixed gun/radar controller every turn.
 */
public class PolicyBot extends TeamRobot {
    private final Map<String, double[]> enemies = new LinkedHashMap<>();
    /** Names that sent us a message: team-mates. Robocode 1.9.3.9's own list misses the mates of a team that is
     *  not first in the battle (its members carry a per-class count, the robots their battle index), so every
     *  PolicyBot announces itself in its first turn. */
    private final Set<String> heard = new HashSet<>();

    @Override
    public void run() {
        RobotParts.start(this);
        PolicyModel model;
        try (Reader r = RobotParts.embedded(this, "PolicyData", "policy.txt")) {
            model = PolicyModel.read(r);
        } catch (IOException | RuntimeException e) {
            RobotParts.idle(this, "policy-load-failed", e);
            return;
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
            double[][] e = enemies.values().toArray(new double[0][]);
            long turn = getTime() + 1;  // the commands set now take effect in this turn
            if ((turn - 1) % step == 0) {
                int a = model.act(getX(), getY(), getHeadingRadians(), getEnergy(), e, getBattleFieldWidth(),
                        getBattleFieldHeight());
                double[] mv = model.move(a);
                setAhead(mv[0]);
                setTurnRightRadians(mv[1]);
            }
            RobotParts.command(this, model.gunRadar(getX(), getY(), getGunHeadingRadians(),
                    getRadarHeadingRadians(), getGunHeat(), getEnergy(), e));
            execute();
        }
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
