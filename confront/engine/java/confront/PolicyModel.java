package confront;

import java.io.IOException;
import java.io.Reader;

/**
 * An exported policy (no Robocode dependency): the paper's state features, a Q table or an MLP, the four
 * macro moves and the fixed gun/radar controller. Mirrors confront.engine.export.ExportedPolicy; the file
 * format is written by confront.engine.export.
 */
public final class PolicyModel {
    static final double TWO_PI = Aim.TWO_PI;
    final ModelFile file;
    final Aim aim;
    final String kind;
    double[][] q;
    Mlp mlp;

    private PolicyModel(ModelFile file) {
        this.file = file;
        this.aim = new Aim(file);
        this.kind = file.text("kind", null);
    }

    public static PolicyModel read(Reader source) throws IOException {
        PolicyModel m = new PolicyModel(ModelFile.read(source, "confront-policy 1", "policy"));
        m.q = m.file.take("q");
        if ("mlp".equals(m.kind)) {
            m.mlp = m.file.mlp(m.file.text("hidden_activation", null), m.file.text("output_activation", null),
                    m.num("act_a"), m.num("act_b"));
        } else if (!"qtable".equals(m.kind) || m.q == null) {
            throw new IOException("policy kind must be qtable (with matrix q) or mlp, got " + m.kind);
        }
        m.file.allTaken();
        return m;
    }

    double num(String key) {
        return file.num(key);
    }

    public int stepTurns() {
        return (int) num("step_turns");
    }

    double maxDistance(double width, double height) {
        double d = num("max_distance");
        return d > 0 ? d : Math.hypot(width, height);
    }

    /** The paper's discrete state 0..319 (confront.arena.observe.discrete_state) toward enemies[t] (-1: none). */
    int state(double x, double y, double heading, int t, double[][] enemies, double dmax) {
        double rel = 0.0;
        double dist = 0.0;
        if (t >= 0) {
            dist = Math.hypot(enemies[t][0] - x, enemies[t][1] - y);
            rel = Aim.absAngle(Aim.absAngle(Math.atan2(enemies[t][0] - x, enemies[t][1] - y)) - heading);
        }
        int relBin = Math.min((int) (Aim.absAngle(rel + TWO_PI / 8) / (TWO_PI / 4)), 3);
        int headBin = Math.min((int) (Aim.absAngle(heading) / (TWO_PI / 4)), 3);
        int distBin = (int) Math.max(0, Math.min(19, Math.floor(dist * (20 / dmax))));
        return (relBin * 4 + headBin) * 20 + distBin;
    }

    /** Continuous features (float32 like the Python side), see confront.arena.observe.features. */
    double[] features(double x, double y, double heading, double energy, int t, double[][] enemies, double dmax,
                      double width, double height) {
        double rel = 0.0;
        double dist = 0.0;
        if (t >= 0) {
            dist = Math.hypot(enemies[t][0] - x, enemies[t][1] - y);
            rel = Aim.absAngle(Aim.absAngle(Math.atan2(enemies[t][0] - x, enemies[t][1] - y)) - heading);
        }
        boolean pos = num("include_position") != 0;
        double[] f = new double[pos ? 9 : 7];
        f[0] = Math.sin(rel);
        f[1] = Math.cos(rel);
        f[2] = Math.sin(heading);
        f[3] = Math.cos(heading);
        f[4] = Math.min(dist / dmax, 1.0);
        f[5] = energy / 100.0;
        f[6] = t >= 0 ? enemies[t][2] / 100.0 : 0.0;
        if (pos) {
            f[7] = x / width;
            f[8] = y / height;
        }
        for (int i = 0; i < f.length; i++) {
            f[i] = (float) f[i];
        }
        return f;
    }

    /** Action values for one observation: the Q table's row, or the MLP on the inputs. */
    double[] values(int state, double[] inputs) {
        return q != null ? q[state] : mlp.forward(inputs);
    }

    /** The nearest of the enemies (the only target rule exported). */
    private int target(double x, double y, double[][] enemies) {
        if (!"nearest".equals(file.text("target", null))) {
            throw new IllegalArgumentException("only target=nearest is exported");
        }
        return Aim.nearest(x, y, enemies);
    }

    /** The discrete state (0..319) for own position and heading and the enemies' last known rows {x, y, energy}:
     *  the row of a Q table that {@link #moveValues} reads. */
    public int moveState(double x, double y, double heading, double[][] enemies, double width, double height) {
        return state(x, y, heading, target(x, y, enemies), enemies, maxDistance(width, height));
    }

    /** The four move values for own state and the enemies' last known rows {x, y, energy}. */
    public double[] moveValues(double x, double y, double heading, double energy, double[][] enemies, double width,
                               double height) {
        int t = target(x, y, enemies);
        double dmax = maxDistance(width, height);
        int s = state(x, y, heading, t, enemies, dmax);
        double[] in = null;
        if (q == null && "onehot".equals(file.text("inputs", null))) {
            in = new double[320];
            in[s] = 1.0;
        } else if (q == null) {
            in = features(x, y, heading, energy, t, enemies, dmax, width, height);
        }
        return values(s, in);
    }

    /** Greedy move for own state and the enemies' last known rows {x, y, energy}: the first maximum, or with
     *  "ties random" one of the maxima at random (Math.random: the engine's seed does not reach it). */
    public int act(double x, double y, double heading, double energy, double[][] enemies, double width,
                   double height) {
        double[] v = moveValues(x, y, heading, energy, enemies, width, height);
        int best = 0;
        int equal = 1;
        boolean random = "random".equals(file.text("ties", null));
        for (int i = 1; i < v.length; i++) {
            if (v[i] > v[best]) {
                best = i;
                equal = 1;
            } else if (random && v[i] == v[best] && Math.random() * ++equal < 1.0) {
                best = i;  // reservoir sampling: each of the equal maxima with probability 1/equal
            }
        }
        return best;
    }

    /** (distance, body turn) of a move: 0 forward, 1 backward, 2 clockwise, 3 anticlockwise. */
    public double[] move(int action) {
        double d = num("move_distance");
        double turn = num("turn_angle");
        switch (action) {
            case 0: return new double[] {d, 0.0};
            case 1: return new double[] {-d, 0.0};
            case 2: return new double[] {num("turn_move_distance"), turn};
            case 3: return new double[] {num("turn_move_distance"), -turn};
            default: throw new IllegalArgumentException("action " + action);
        }
    }

    /** (gun turn, radar turn, fire power) of the fixed controller (confront.arena.control.aim) toward the nearest
     *  of the enemies' last known rows, the power by distance band. */
    public double[] gunRadar(double x, double y, double gunHeading, double radarHeading, double gunHeat,
                             double energy, double[][] enemies) {
        int t = Aim.nearest(x, y, enemies);
        if (t < 0) {
            return Aim.none();
        }
        return aim.toward(x, y, enemies[t][0], enemies[t][1], gunHeading, radarHeading, gunHeat, energy, 0.0);
    }
}
