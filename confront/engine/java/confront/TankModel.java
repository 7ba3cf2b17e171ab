package confront;

import java.io.IOException;
import java.io.Reader;

/**
 * An exported tank policy (no Robocode dependency): the tank view of confront.arena.tank.tank_view_row, the
 * actor MLP (tanh hidden layers, linear logits), the greedy tank action (argmax per head: distance, body turn,
 * fire power, enemy slot, gun lead) or, with "play sampled", a draw from each head's softmax (sample), and the gun/radar controller of confront.arena.smdp.controller_turn with
 * the lead of confront.arena.tank.lead_point (none, linear or circular).
 * Mirrors confront.engine.tank_export.TankPolicy; the file format is written by its to_text().
 *
 * <p>Skills (opt-in keys, absent in older files: off): "surf 1" (the distance head's extra last entry: the body
 * follows the technique brain's movement), the lead "gf" (the brain's GuessFactor aim), "knowledge 1" (the brain's
 * knowledge block at the end of the view), "brain SurfAS" (the brain's gun: GuessFactor beside anti-surfer GuessFactor;
 * absent: SurfGF); see confront.arena.tank and TankBot.
 *
 * <p>Angles follow Robocode: radians, 0 = north (+y), clockwise. Enemy rows are {x, y, energy, heading,
 * velocity, energy drop, scan time, turn rate} of the last scan this round (turnRate: see turnRate()); mate rows
 * are {x, y, energy}.
 */
public final class TankModel {
    static final int OWN = 11;
    static final int ENEMY = 9;
    static final int MATE = 5;
    static final double MAX_AGE = 50.0;
    static final double WALL_MARGIN = 18.0;
    static final double MAX_RATE = Math.PI / 18.0;  // Rules.MAX_TURN_RATE, 10 deg/turn
    static final int LEAD_NONE = 0;
    static final int LEAD_LINEAR = 1;
    static final int LEAD_CIRCULAR = 2;
    static final int LEAD_GF = 3;
    static final int KNOWLEDGE = 8;  // TechBrain.KNOWLEDGE

    final Mlp actor;
    final Aim aim;
    final double[] distances;
    final double[] turns;  // radians
    final double[] powers;  // fire powers as given (0 = hold)
    final int enemySlots;
    final int mateSlots;
    final int stepTurns;
    final int[] leads;  // the lead head's choices: LEAD_NONE, LEAD_LINEAR, LEAD_CIRCULAR
    final boolean turnToTarget;  // turn_mode target: the body turn is an angle to the target's bearing
    final boolean sampled;  // "play sampled": act draws each head from its softmax (sample), else greedy (act)
    final boolean surf;  // the distance head's extra last entry: the body follows the brain's movement
    final boolean knowledge;  // the view ends with the brain's knowledge block
    final String brain;  // the technique robot the skills follow: SurfGF, or SurfAS (its gun beside an anti-surfer one)

    private TankModel(ModelFile f) throws IOException {
        distances = f.list("distances");
        double[] deg = f.list("turns_deg");
        turns = new double[deg.length];
        for (int i = 0; i < deg.length; i++) {
            turns[i] = Math.toRadians(deg[i]);
        }
        powers = f.list("fire_powers");
        enemySlots = (int) f.num("enemy_slots");
        mateSlots = (int) f.num("mate_slots");
        stepTurns = (int) f.num("step_turns");
        turnToTarget = "target".equals(f.choice("turn_mode", null, "target", "body"));
        String[] names = f.text("leads", "").trim().split(" ");
        leads = new int[names.length];
        for (int i = 0; i < names.length; i++) {
            leads[i] = lead(names[i]);
        }
        aim = new Aim(f);
        sampled = "sampled".equals(f.choice("play", "greedy", "greedy", "sampled"));
        surf = "1".equals(f.choice("surf", "0", "0", "1"));
        knowledge = "1".equals(f.choice("knowledge", "0", "0", "1"));
        brain = f.choice("brain", "SurfGF", "SurfGF", "SurfAS");
        actor = f.mlp("tanh", "linear", 0.0, 0.0);
        f.allTaken();
        int heads = 0;
        for (int n : dims()) {
            heads += n;
        }
        actor.check(nFeatures(), heads);
    }

    private static int lead(String name) throws IOException {
        switch (name) {
            case "none": return LEAD_NONE;
            case "linear": return LEAD_LINEAR;
            case "circular": return LEAD_CIRCULAR;
            case "gf": return LEAD_GF;
            default: throw new IOException("leads must be none, linear, circular or gf, got " + name);
        }
    }

    /** Reads a "confront-tank 1" policy file. */
    public static TankModel read(Reader source) throws IOException {
        return new TankModel(ModelFile.read(source, "confront-tank 1", "tank policy"));
    }

    public int stepTurns() {
        return stepTurns;
    }

    /** Tank view length: 11 + 9 K + 5 M (+ 8 with knowledge). */
    public int nFeatures() {
        return OWN + ENEMY * enemySlots + MATE * mateSlots + (knowledge ? KNOWLEDGE : 0);
    }

    /** Sizes of the five heads: distance (+ surf), turn, fire power, enemy slot, lead. */
    public int[] dims() {
        return new int[] {distances.length + (surf ? 1 : 0), turns.length, powers.length, enemySlots, leads.length};
    }

    /** Whether the tank carries a technique brain (a gf lead, surf or knowledge). */
    public boolean skills() {
        if (surf || knowledge) {
            return true;
        }
        for (int l : leads) {
            if (l == LEAD_GF) {
                return true;
            }
        }
        return false;
    }

    /** The view with the brain's knowledge block (TechBrain.knowledge) at its end (knowledge null: left 0). */
    public double[] view(double x, double y, double heading, double velocity, double energy, double gunHeat,
                         int enemiesAlive, int enemiesStart, int matesAlive, int matesStart, double[][] enemies,
                         double[][] mates, double time, double width, double height, int[] slots, double[] known) {
        double[] out = view(x, y, heading, velocity, energy, gunHeat, enemiesAlive, enemiesStart, matesAlive,
                matesStart, enemies, mates, time, width, height, slots);
        if (knowledge && known != null) {
            System.arraycopy(known, 0, out, out.length - KNOWLEDGE, KNOWLEDGE);
        }
        return out;
    }

    /**
     * The tank view (tank_view_row, in double precision). enemies: the enemies known (alive, scanned this
     * round), rows {x, y, energy, heading, velocity, drop, scan time, turn rate}; mates: living team-mates
     * {x, y, energy}.
     * Slots are filled nearest first, ties to the lower row; slots[k] gets the enemy row of slot k (-1 empty).
     */
    public double[] view(double x, double y, double heading, double velocity, double energy, double gunHeat,
                         int enemiesAlive, int enemiesStart, int matesAlive, int matesStart, double[][] enemies,
                         double[][] mates, double time, double width, double height, int[] slots) {
        double[] out = new double[nFeatures()];
        double diag = Math.hypot(width, height);
        out[0] = x / width;
        out[1] = y / height;
        out[2] = (width - x) / width;
        out[3] = (height - y) / height;
        out[4] = Math.sin(heading);
        out[5] = Math.cos(heading);
        out[6] = velocity / 8.0;
        out[7] = energy / 100.0;
        out[8] = gunHeat / 3.0;
        out[9] = enemiesStart > 0 ? (double) enemiesAlive / enemiesStart : 0.0;
        out[10] = matesStart > 0 ? (double) matesAlive / matesStart : 0.0;
        for (int s = 0; s < slots.length; s++) {
            slots[s] = -1;
        }
        boolean[] used = new boolean[enemies.length];
        for (int s = 0; s < enemySlots; s++) {
            int best = nextNearest(x, y, enemies, used);
            if (best < 0) {
                break;
            }
            if (s < slots.length) {
                slots[s] = best;
            }
            double[] e = enemies[best];
            int o = OWN + ENEMY * s;
            double bearing = Math.atan2(e[0] - x, e[1] - y);
            double rel = bearing - heading;
            double relH = e[3] - bearing;
            out[o] = 1.0;
            out[o + 1] = Math.sin(rel);
            out[o + 2] = Math.cos(rel);
            out[o + 3] = Math.min(Math.hypot(e[0] - x, e[1] - y) / diag, 1.0);
            out[o + 4] = e[4] * Math.sin(relH) / 8.0;
            out[o + 5] = e[4] * Math.cos(relH) / 8.0;
            out[o + 6] = e[2] / 100.0;
            out[o + 7] = Math.min(time - e[6], MAX_AGE) / MAX_AGE;
            out[o + 8] = Math.min(Math.max(e[5], 0.0), 3.0) / 3.0;
        }
        used = new boolean[mates.length];
        for (int s = 0; s < mateSlots; s++) {
            int best = nextNearest(x, y, mates, used);
            if (best < 0) {
                break;
            }
            int o = OWN + ENEMY * enemySlots + MATE * s;
            double rel = Math.atan2(mates[best][0] - x, mates[best][1] - y) - heading;
            out[o] = 1.0;
            out[o + 1] = Math.sin(rel);
            out[o + 2] = Math.cos(rel);
            out[o + 3] = Math.min(Math.hypot(mates[best][0] - x, mates[best][1] - y) / diag, 1.0);
            out[o + 4] = mates[best][2] / 100.0;
        }
        return out;
    }

    /** The nearest row not used yet by distance (Math.hypot; first of equals), marked used; -1 if none. */
    private static int nextNearest(double x, double y, double[][] rows, boolean[] used) {
        int best = -1;
        double bestD = Double.POSITIVE_INFINITY;
        for (int j = 0; j < rows.length; j++) {
            if (used[j]) {
                continue;
            }
            double d = Math.hypot(rows[j][0] - x, rows[j][1] - y);
            if (d < bestD) {
                best = j;
                bestD = d;
            }
        }
        if (best >= 0) {
            used[best] = true;
        }
        return best;
    }

    /** Actor logits for a view; the view is rounded to float32 first, as the simulator hands it to the learner. */
    public double[] logits(double[] view) {
        double[] h = new double[view.length];
        for (int i = 0; i < view.length; i++) {
            h[i] = (float) view[i];
        }
        return actor.forward(h);
    }

    /** Greedy joint action (((d * nt + t) * nf + f) * K + k) * nl + l: the first maximum of each head's logits. */
    public int act(double[] view) {
        double[] z = logits(view);
        int[] d = dims();
        int joint = 0;
        int off = 0;
        for (int head = 0; head < d.length; head++) {
            int best = 0;
            for (int i = 1; i < d[head]; i++) {
                if (z[off + i] > z[off + best]) {
                    best = i;
                }
            }
            joint = joint * d[head] + best;
            off += d[head];
        }
        return joint;
    }

    /**
     * Joint action with each head drawn from the softmax of its logits by one uniform draw u[head] in [0, 1): the
     * first choice whose running sum of probabilities (exp(z - max z) over their sum) exceeds the draw, else the
     * last (tank_export.sample_heads).
     */
    public int sample(double[] view, double[] u) {
        double[] z = logits(view);
        int[] d = dims();
        int joint = 0;
        int off = 0;
        for (int head = 0; head < d.length; head++) {
            double top = z[off];
            for (int i = 1; i < d[head]; i++) {
                top = Math.max(top, z[off + i]);
            }
            double[] w = new double[d[head]];
            double total = 0.0;
            for (int i = 0; i < d[head]; i++) {
                w[i] = StrictMath.exp(z[off + i] - top);
                total += w[i];
            }
            int pick = d[head] - 1;
            double acc = 0.0;
            for (int i = 0; i < d[head]; i++) {
                acc += w[i] / total;
                if (u[head] < acc) {
                    pick = i;
                    break;
                }
            }
            joint = joint * d[head] + pick;
            off += d[head];
        }
        return joint;
    }

    /** Whether the policy file asks for sampled play ("play sampled"), else greedy. */
    public boolean sampled() {
        return sampled;
    }

    /**
     * (distance, body turn rad, fire power (-1 = hold), enemy slot, lead (LEAD_*), 1 = the body surfs (distance
     * 0)) of a joint action (action_table; the body turn as given, see bodyTurn).
     */
    public double[] decode(int action) {
        int[] d = dims();
        int[] idx = new int[d.length];
        int rest = action;
        for (int head = d.length - 1; head >= 0; head--) {
            idx[head] = rest % d[head];
            rest /= d[head];
        }
        double p = powers[idx[2]];
        boolean surfs = idx[0] >= distances.length;
        return new double[] {surfs ? 0.0 : distances[idx[0]], turns[idx[1]], p > 0 ? p : -1.0, idx[3], leads[idx[4]],
                surfs ? 1.0 : 0.0};
    }

    /**
     * The lead (lead_point): where an enemy scanned at (mx, my) heading mh at velocity mv age turns ago, turning
     * rate rad/turn (0 = linear), is when a bullet of the power reaches it; clipped to where a robot's centre
     * can be; 10 fixed-point iterations.
     */
    public static double[] leadPoint(double x, double y, double mx, double my, double mh, double mv, double rate,
                                     double age, double power, double width, double height) {
        double speed = 20.0 - 3.0 * power;
        double px = mx;
        double py = my;
        double t = 0.0;
        for (int i = 0; i < 10; i++) {
            double tau = age + t;
            double ox;
            double oy;
            if (Math.abs(rate) < 1e-9) {
                ox = Math.sin(mh) * mv * tau;
                oy = Math.cos(mh) * mv * tau;
            } else {
                ox = mv / rate * (Math.cos(mh) - Math.cos(mh + rate * tau));
                oy = mv / rate * (Math.sin(mh + rate * tau) - Math.sin(mh));
            }
            px = Math.min(Math.max(mx + ox, WALL_MARGIN), width - WALL_MARGIN);
            py = Math.min(Math.max(my + oy, WALL_MARGIN), height - WALL_MARGIN);
            t = Math.hypot(px - x, py - y) / speed;
        }
        return new double[] {px, py};
    }

    /**
     * An enemy's turn rate at a new scan (observe.remember_scans): the heading change since the previous scan
     * this round over the turns between them, within +-10 deg/turn; 0 without a previous scan.
     */
    public static double turnRate(double[] prev, double heading, double time) {
        if (prev == null) {
            return 0.0;
        }
        double dt = time - prev[6];
        if (!(dt > 0)) {
            return 0.0;
        }
        double dh = Aim.relAngle(heading - prev[3]);
        return Math.min(Math.max(dh / dt, -MAX_RATE), MAX_RATE);
    }

    /**
     * The body turn to command at the start of a step for the action's turn (rad, + clockwise): with turn_mode
     * target and a target (enemies[tgt]), the turn that puts the body at that angle to the target's bearing
     * from its last scanned position, wrapped to [-pi, pi); else the turn itself.
     */
    public double bodyTurn(double x, double y, double heading, double[][] enemies, int tgt, double turn) {
        if (!turnToTarget || tgt < 0) {
            return turn;
        }
        double bearing = Math.atan2(enemies[tgt][0] - x, enemies[tgt][1] - y);
        return Aim.relAngle(bearing + turn - heading);
    }

    /** The row to aim at: chosen when it is a known enemy (>= 0), else the nearest known (first of equals), -1. */
    public static int target(double x, double y, double[][] enemies, int chosen) {
        return chosen >= 0 && chosen < enemies.length ? chosen : Aim.nearest(x, y, enemies);
    }

    /**
     * (gun turn, radar turn, fire power) of the controller (controller_turn) toward enemies[tgt] (tgt -1: none:
     * NaN = keep the gun, a full radar turn, no fire), with the step's lead (LEAD_*; the turn rate only when
     * circular). power: the step's chosen power (-1 = hold, 0 = by distance band).
     */
    public double[] control(double x, double y, double gunHeading, double radarHeading, double gunHeat,
                            double energy, double[][] enemies, int tgt, double power, int lead, double time,
                            double width, double height) {
        return control(x, y, gunHeading, radarHeading, gunHeat, energy, enemies, tgt, power, lead, Double.NaN, time,
                width, height);
    }

    /**
     * control() with the lead gf: {@code gunAim} is the brain's GuessFactor angle for the target (absolute, NaN:
     * none this turn: then circular).
     */
    public double[] control(double x, double y, double gunHeading, double radarHeading, double gunHeat,
                            double energy, double[][] enemies, int tgt, double power, int lead, double gunAim,
                            double time, double width, double height) {
        if (tgt < 0) {
            return Aim.none();
        }
        double[] e = enemies[tgt];
        if (lead == LEAD_GF && !Double.isNaN(gunAim)) {
            return aim.toward(x, y, e[0], e[1], gunAim, gunHeading, radarHeading, gunHeat, energy, power);
        }
        double tx = e[0];
        double ty = e[1];
        if (lead != LEAD_NONE) {
            double rate = lead == LEAD_CIRCULAR || lead == LEAD_GF ? e[7] : 0.0;  // gf without an aim: circular
            double[] p = leadPoint(x, y, tx, ty, e[3], e[4], rate, time - e[6], power > 0 ? power : 2.0, width,
                    height);
            tx = p[0];
            ty = p[1];
        }
        return aim.toward(x, y, tx, ty, gunHeading, radarHeading, gunHeat, energy, power);
    }
}
