package confront;

import java.io.File;
import java.io.FileInputStream;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.InputStreamReader;
import java.io.OutputStream;
import java.io.Reader;
import java.nio.charset.StandardCharsets;
import java.util.HashSet;
import java.util.LinkedHashMap;
import java.util.Map;
import java.util.Set;

import robocode.BulletHitEvent;
import robocode.DeathEvent;
import robocode.HitByBulletEvent;
import robocode.MessageEvent;
import robocode.RobotDeathEvent;
import robocode.RoundEndedEvent;
import robocode.ScannedRobotEvent;
import robocode.TeamRobot;
import robocode.util.Utils;

import confront.tech.TechBrain;

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
 * <p>With skills (TankModel: surf, the lead gf, knowledge) the tank carries a technique brain
 * (confront.tech.TechBrain, the decisions of SurfGF or SurfAS (TankModel.brain); confront.arena.tank): every turn it is given the turn's events and
 * decides (after the view of a decision turn is made, before any command is set); its commands are proposed, not
 * sent: the body follows its movement during a step whose distance is surf, the gun its GuessFactor aim at the
 * target with the lead gf, and its knowledge block ends the view. The tank's controller drives the radar.
 *
 * <p>Robocode makes a new robot object each round, so the memory starts empty every round (the brain's battle
 * memory lives in TechBrain's static fields: one class load per battle). A team-mate's
 * broadcast arrives one turn later, so mates are seen as they were a turn ago (and not at all at turn 0).
 *
 * <p>Training in the engine (confront.train.ppo_engine; needs -DNOSECURITY=true): the JVM property
 * confront.tank.model names a policy file read instead of TankData, and confront.tank.log a folder where each
 * robot appends one line per decision to its own file (LOG_SUFFIX): name, round, turn, joint action, the view
 * (Double.toString, exact), the uniform draws, and with confront.tank.log.detail=true what the view was made
 * from (TankCheck's "V" request: own values, enemy rows, mate rows), tab-separated.
 */
public class TankBot extends TeamRobot {
    static final String MODEL_PROPERTY = "confront.tank.model";
    static final String LOG_PROPERTY = "confront.tank.log";
    static final String DETAIL_PROPERTY = "confront.tank.log.detail";
    static final String LOG_SUFFIX = ".decisions";
    /** name: {x, y, energy, heading, velocity, energy drop, scan time, turn rate} of the last scan this round. */
    private final Map<String, double[]> enemies = new LinkedHashMap<>();
    /** name: {x, y, energy} of the latest message this round. */
    private final Map<String, double[]> mates = new LinkedHashMap<>();
    private final Set<String> deadMates = new HashSet<>();
    private final Set<String> heard = new HashSet<>();  // names that sent us a message: team-mates
    private int decisions;
    private int shots;
    private long turns;  // turns played this round, and the time spent deciding them (ns): total, the first turn's
    private long busyNs;  // (Robocode gives it 10 times the time) and the longest of the others
    private long firstNs;
    private long longestNs;
    private int slowTurns;  // turns that took over 1 ms
    private long longestAt;  // the turn (getTime()) of the longest
    private OutputStream log;  // the decision log of this round (confront.tank.log), opened at the first decision
    private boolean detail;
    private TechBrain brain;  // the technique brain of a tank with skills (null without)
    private boolean dead;  // set by onDeath: the brain decides nothing more

    @Override
    public void run() {
        RobotParts.start(this);
        TankModel model;
        try (Reader r = source()) {
            model = TankModel.read(r);
        } catch (IOException | RuntimeException e) {
            RobotParts.idle(this, "tank-load-failed", e);
            return;
        }
        String logDir = property(LOG_PROPERTY);
        detail = "true".equals(property(DETAIL_PROPERTY));
        String[] team = getTeammates();
        int matesStart = team == null ? 0 : team.length;
        int enemiesStart = Math.max(getOthers() - matesStart, 0);
        int step = model.stepTurns();
        int[] slots = new int[model.enemySlots];
        String chosen = null;
        double power = -1.0;
        int lead = TankModel.LEAD_NONE;
        boolean surfing = false;
        if (model.skills()) {
            TechBrain.startBattle(getX(), getY());
            int gun = "SurfAS".equals(model.brain) ? TechBrain.G_AS : TechBrain.G_GF;
            brain = new TechBrain(gun, TechBrain.M_SURF, getBattleFieldWidth(), getBattleFieldHeight());
        }
        long next = 0;  // the next decision turn: 0, step, 2 step, ... (a skipped decision turn is made up at once)
        while (true) {
            long started = System.nanoTime();
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
                            getBattleFieldWidth(), getBattleFieldHeight(), slots,
                            brain != null ? brain.knowledge(getX(), getY(), getTime()) : null);
                    double[] u = model.sampled() ? draws(model.dims().length) : new double[0];
                    int joint = model.sampled() ? model.sample(v, u) : model.act(v);
                    if (logDir != null) {
                        logDecision(logDir, time, joint, v, u, enemiesStart, matesAlive, matesStart, known);
                    }
                    a = model.decode(joint);
                    power = a[2];
                    lead = (int) a[4];
                    surfing = a[5] > 0;
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
                boolean thinks = brain != null && !dead;
                if (thinks) {  // the brain's turn, on the robot's state before any command of this turn
                    brain.decide(getTime(), getX(), getY(), getHeadingRadians(), getVelocity(), getEnergy(),
                            getGunHeadingRadians(), getGunHeat(), getGunTurnRemainingRadians(),
                            getRadarHeadingRadians(), getRadarTurnRemainingRadians(), getOthers());
                }
                if (thinks && surfing) {  // the body follows the brain every turn of the step
                    if (!Double.isNaN(brain.cmd[0])) {
                        setAhead(brain.cmd[0]);
                    }
                    if (!Double.isNaN(brain.cmd[1])) {
                        setTurnRightRadians(brain.cmd[1]);
                    }
                } else if (decide) {
                    setAhead(a[0]);
                    setTurnRightRadians(model.bodyTurn(getX(), getY(), getHeadingRadians(), known, tgt, a[1]));
                }
                double gunAim = thinks && lead == TankModel.LEAD_GF && tgt >= 0
                        ? brain.guessAim(brain.slotOf(names[tgt]), power > 0 ? power : 2.0) : Double.NaN;
                if (RobotParts.command(this, model.control(getX(), getY(), getGunHeadingRadians(),
                        getRadarHeadingRadians(), getGunHeat(), getEnergy(), known, tgt, power, lead, gunAim, time,
                        getBattleFieldWidth(), getBattleFieldHeight()))) {
                    shots++;
                }
                if (brain != null) {
                    brain.endTurn();
                }
            } catch (RuntimeException e) {
                out.println("CONFRONT tank-error " + e);
                throw e;
            }
            long spent = System.nanoTime() - started;
            turns++;
            busyNs += spent;
            if (turns == 1) {
                firstNs = spent;
            } else if (spent > longestNs) {
                longestNs = spent;
                longestAt = getTime();
            }
            slowTurns += spent > 1_000_000L ? 1 : 0;
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

    /** A JVM property, or null (also when the sandbox refuses to tell). */
    private static String property(String name) {
        try {
            String v = System.getProperty(name);
            return v == null || v.isEmpty() ? null : v;
        } catch (SecurityException e) {
            return null;
        }
    }

    /** One line of the decision log (see the class comment); written at once, unbuffered (a robot's thread may
     *  be stopped at any time). */
    private void logDecision(String dir, double time, int joint, double[] v, double[] u, int enemiesStart,
                             int matesAlive, int matesStart, double[][] known) {
        StringBuilder b = new StringBuilder(2048);
        b.append(getName()).append('\t').append(getRoundNum()).append('\t').append((long) time).append('\t')
                .append(joint).append('\t');
        join(b, v);
        b.append('\t');
        join(b, u);
        if (detail) {
            b.append('\t');
            join(b, new double[] {getX(), getY(), getHeadingRadians(), getVelocity(), getEnergy(), getGunHeat(),
                    Math.max(getOthers() - matesAlive, 0), enemiesStart, matesAlive, matesStart, time,
                    getBattleFieldWidth(), getBattleFieldHeight()});
            b.append('\t');
            rows(b, known);
            b.append('\t');
            rows(b, mates.values().toArray(new double[0][]));
        }
        b.append('\n');
        try {
            if (log == null) {
                String safe = getName().replaceAll("[^A-Za-z0-9._-]", "_");
                log = new FileOutputStream(new File(dir, safe + LOG_SUFFIX), true);
            }
            log.write(b.toString().getBytes(StandardCharsets.UTF_8));
        } catch (IOException e) {
            out.println("CONFRONT tank-error log " + e);
        }
    }

    private static void join(StringBuilder b, double[] v) {
        for (int i = 0; i < v.length; i++) {
            if (i > 0) {
                b.append(' ');
            }
            b.append(Double.toString(v[i]));
        }
    }

    private static void rows(StringBuilder b, double[][] rows) {
        for (int i = 0; i < rows.length; i++) {
            if (i > 0) {
                b.append('|');
            }
            join(b, rows[i]);
        }
    }

    private void closeLog() {
        if (log != null) {
            try {
                log.close();
            } catch (IOException e) {
                out.println("CONFRONT tank-error log " + e);
            }
            log = null;
        }
    }

    /** The policy file named by confront.tank.model, else the one compiled into confront.TankData (written at
     *  export), else tank_policy.txt beside the class. */
    private Reader source() throws IOException {
        String path = property(MODEL_PROPERTY);
        if (path != null) {
            return new InputStreamReader(new FileInputStream(path), StandardCharsets.UTF_8);
        }
        return RobotParts.embedded(this, "TankData", "tank_policy.txt");
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
            if (brain != null) {
                brain.onScanned(e.getName(), e.getBearingRadians(), e.getDistance(), e.getHeadingRadians(),
                        e.getVelocity(), e.getEnergy(), getTime(), mate(e.getName()), getX(), getY(),
                        getHeadingRadians());
            }
            remember(e);
        } catch (RuntimeException x) {
            out.println("CONFRONT tank-error scan " + x);
        }
    }

    @Override
    public void onHitByBullet(HitByBulletEvent e) {
        if (brain != null) {
            brain.onHitByBullet(e.getBullet().getPower(), e.getBullet().getHeadingRadians());
        }
    }

    @Override
    public void onBulletHit(BulletHitEvent e) {
        if (brain != null) {
            brain.onBulletHit(e.getBullet().getPower());
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
        if (brain != null) {
            brain.onRobotDeath(name);
        }
        enemies.remove(name);
        if (mate(name)) {
            mates.remove(name);
            deadMates.add(name);
        }
    }

    @Override
    public void onDeath(DeathEvent e) {
        dead = true;
        closeLog();
    }

    @Override
    public void onRoundEnded(RoundEndedEvent e) {
        closeLog();
        out.println("CONFRONT tank-round decisions=" + decisions + " shots=" + shots + " turn_us_mean="
                + (turns > 0 ? busyNs / turns / 1000 : 0) + " first_turn_us=" + firstNs / 1000 + " turn_us_max=" + longestNs / 1000 + " at_turn=" + longestAt
                + " turns_over_1ms="
                + slowTurns + " turns=" + turns);
    }
}
