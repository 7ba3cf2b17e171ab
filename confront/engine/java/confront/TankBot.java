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
import robocode.RoundEndedEvent;
import robocode.ScannedRobotEvent;
import robocode.TeamRobot;
import robocode.util.Utils;

/**
 * A tank policy trained with confront (PPO over the tank view and tank actions), running with no Python.
 * Its policy is compiled into confront.TankData at export. Every step_turns turns it builds the tank view
 * (confront.arena.tank) from what it knows: its own getters, the last ScannedRobotEvent of each living enemy
 * this round (position, energy, heading, velocity, the energy drop and turn rate since the previous scan, the
 * scan time) and the latest (x, y, energy) each living team-mate broadcast; it picks the greedy tank action (or,
 * exported with play sampled, draws it from the policy with Robocode's seeded random)
 * (move, body turn by an angle or to an angle from the target's bearing, fire power or hold, target slot, gun
 * lead). Every turn the gun/radar controller aims at the chosen target (the nearest known enemy when that one
 * is unknown or dead), with the step's lead (none, linear or circular).
 *
 * <p>Robocode makes a new robot object each round, so the memory starts empty every round. A team-mate's
 * broadcast arrives one turn later, so mates are seen as they were a turn ago (and not at all at turn 0).
 */
public class TankBot extends TeamRobot {
    /** name: {x, y, energy, heading, velocity, energy drop, scan time, turn rate} of the last scan this round. */
    private final Map<String, double[]> enemies = new LinkedHashMap<>();
    /** name: {x, y, energy} of the latest message this round. */
    private final Map<String, double[]> mates = new LinkedHashMap<>();
    private final Set<String> deadMates = new HashSet<>();
    private final Set<String> heard = new HashSet<>();  // names that sent us a message: team-mates
    private int decisions;
    private int shots;

    @Override
    public void run() {
        setAdjustGunForRobotTurn(true);
        setAdjustRadarForRobotTurn(true);
        setAdjustRadarForGunTurn(true);
        RoundStart.awaitEngine();
        TankModel model;
        try {
            model = load();
        } catch (IOException | RuntimeException e) {
            out.println("CONFRONT tank-load-failed " + e);
            while (true) {
                setTurnRadarRightRadians(2 * Math.PI);
                execute();
            }
        }
        String[] team = getTeammates();
        int matesStart = team == null ? 0 : team.length;
        int enemiesStart = Math.max(getOthers() - matesStart, 0);
        int step = model.stepTurns();
        int[] slots = new int[model.enemySlots];
        String chosen = null;
        double power = -1.0;
        int lead = TankModel.LEAD_NONE;
        long next = 0;  // the next decision turn: 0, step, 2 step, ... (a skipped decision turn is made up at once)
        while (true) {
            try {
                broadcast();
                String[] names = enemies.keySet().toArray(new String[0]);
                double[][] known = enemies.values().toArray(new double[0][]);
                double time = getTime();
                boolean decide = getTime() >= next;  // PolicyBot's phase: commands set now act in turn getTime()+1
                double[] a = null;
                if (decide) {
                    next = (getTime() / step + 1) * step;
                    int matesAlive = Math.max(matesStart - deadMates.size(), 0);
                    double[] v = model.view(getX(), getY(), getHeadingRadians(), getVelocity(), getEnergy(),
                            getGunHeat(), Math.max(getOthers() - matesAlive, 0), enemiesStart, matesAlive,
                            matesStart, known, mates.values().toArray(new double[0][]), time,
                            getBattleFieldWidth(), getBattleFieldHeight(), slots);
                    a = model.decode(model.sampled() ? model.sample(v, draws(model.dims().length)) : model.act(v));
                    power = a[2];
                    lead = (int) a[4];
                    int k = (int) a[3];
                    chosen = slots[k] >= 0 ? names[slots[k]] : null;
                    decisions++;
                }
                int c = -1;
                for (int j = 0; j < names.length; j++) {
                    if (names[j].equals(chosen)) {
                        c = j;
                    }
                }
                int tgt = TankModel.target(getX(), getY(), known, c);
                if (decide) {
                    setAhead(a[0]);
                    setTurnRightRadians(model.bodyTurn(getX(), getY(), getHeadingRadians(), known, tgt, a[1]));
                }
                double[] g = model.control(getX(), getY(), getGunHeadingRadians(), getRadarHeadingRadians(),
                        getGunHeat(), getEnergy(), known, tgt, power, lead, time, getBattleFieldWidth(),
                        getBattleFieldHeight());
                if (!Double.isNaN(g[0])) {
                    setTurnGunRightRadians(g[0]);
                }
                setTurnRadarRightRadians(g[1]);
                if (g[2] > 0) {
                    setFire(g[2]);
                    shots++;
                }
            } catch (RuntimeException e) {
                out.println("CONFRONT tank-error " + e);
                throw e;
            }
            execute();
        }
    }

    /** One uniform draw in [0, 1) per action head from Robocode's random (seeded by the battle's seed). */
    private static double[] draws(int heads) {
        java.util.Random rng = Utils.getRandom();
        double[] u = new double[heads];
        for (int i = 0; i < heads; i++) {
            u[i] = rng.nextDouble();
        }
        return u;
    }

    /** The policy compiled into confront.TankData (written at export), else tank_policy.txt beside the class. */
    private TankModel load() throws IOException {
        try {
            String[] chunks = (String[]) Class.forName("confront.TankData").getField("CHUNKS").get(null);
            return TankModel.read(new StringReader(String.join("", chunks)));
        } catch (ReflectiveOperationException e) {
            InputStream res = getClass().getResourceAsStream("tank_policy.txt");
            if (res == null) {
                throw new IOException("no confront.TankData class and no tank_policy.txt");
            }
            try (Reader r = new InputStreamReader(res, StandardCharsets.UTF_8)) {
                return TankModel.read(r);
            }
        }
    }

    private void broadcast() {
        if (getTeammates() == null) {
            return;
        }
        try {
            broadcastMessage(new double[] {getX(), getY(), getEnergy()});
        } catch (IOException e) {
            out.println("CONFRONT tank-error broadcast " + e);
        }
    }

    @Override
    public void onScannedRobot(ScannedRobotEvent e) {
        try {
            remember(e);
        } catch (RuntimeException x) {
            out.println("CONFRONT tank-error scan " + x);
        }
    }

    /** A team-mate: by the engine's list, or by having sent us a message (only team-mates can). Robocode 1.9.3.9
     *  names the list's members with a per-class count, the robots themselves with their battle index, so the
     *  list misses the mates of a team that is not first in the battle (Battle.createPeers). */
    private boolean mate(String name) {
        return isTeammate(name) || heard.contains(name);
    }

    private void remember(ScannedRobotEvent e) {
        String name = e.getName();
        if (mate(name)) {
            return;
        }
        double abs = getHeadingRadians() + e.getBearingRadians();
        double[] prev = enemies.get(name);
        double drop = prev != null ? prev[2] - e.getEnergy() : 0.0;
        double rate = TankModel.turnRate(prev, e.getHeadingRadians(), e.getTime());
        enemies.put(name, new double[] {getX() + e.getDistance() * Math.sin(abs),
                getY() + e.getDistance() * Math.cos(abs), e.getEnergy(), e.getHeadingRadians(), e.getVelocity(),
                drop, e.getTime(), rate});
    }

    @Override
    public void onMessageReceived(MessageEvent e) {
        String from = e.getSender();
        Object m = e.getMessage();
        if (from == null) {
            return;
        }
        heard.add(from);
        enemies.remove(from);  // scanned before its first message arrived
        if (!deadMates.contains(from) && m instanceof double[] && ((double[]) m).length == 3) {
            mates.put(from, ((double[]) m).clone());
        }
    }

    @Override
    public void onRobotDeath(RobotDeathEvent e) {
        String name = e.getName();
        enemies.remove(name);
        if (mate(name)) {
            mates.remove(name);
            deadMates.add(name);
        }
    }

    @Override
    public void onRoundEnded(RoundEndedEvent e) {
        out.println("CONFRONT tank-round decisions=" + decisions + " shots=" + shots);
    }
}
