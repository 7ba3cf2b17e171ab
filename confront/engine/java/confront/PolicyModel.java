package confront;

import java.io.BufferedReader;
import java.io.IOException;
import java.io.Reader;
import java.util.ArrayList;
import java.util.HashMap;
import java.util.List;
import java.util.Map;

/**
 * An exported policy (no Robocode dependency): the paper's state features, a Q table or an MLP, the four
 * macro moves and the fixed gun/radar controller. Mirrors confront.engine.export.ExportedPolicy; the file
 * format is written by confront.engine.export.
 */
public final class PolicyModel {
    static final double TWO_PI = 2 * Math.PI;
    final Map<String, String> keys = new HashMap<>();
    double[][] q;
    final List<double[][]> weights = new ArrayList<>();
    final List<double[]> biases = new ArrayList<>();
    String kind;
    String hiddenAct;
    String outputAct;
    double actA;
    double actB;

    public static PolicyModel read(Reader source) throws IOException {
        PolicyModel m = new PolicyModel();
        BufferedReader r = new BufferedReader(source);
        String first = r.readLine();
        if (first == null || !first.equals("confront-policy 1")) {
            throw new IOException("not a confront policy file (version 1): " + first);
        }
        String line;
        while ((line = r.readLine()) != null) {
            if (line.isEmpty() || line.startsWith("#")) {
                continue;
            }
            String[] p = line.split(" ");
            if (p[0].equals("matrix")) {
                int rows = Integer.parseInt(p[2]);
                int cols = Integer.parseInt(p[3]);
                double[][] a = new double[rows][cols];
                for (int i = 0; i < rows; i++) {
                    String[] v = r.readLine().split(" ");
                    if (v.length != cols) {
                        throw new IOException("matrix " + p[1] + " row " + i + " has " + v.length + " values");
                    }
                    for (int j = 0; j < cols; j++) {
                        a[i][j] = Double.parseDouble(v[j]);
                    }
                }
                if (p[1].equals("q")) {
                    m.q = a;
                } else if (p[1].startsWith("w")) {
                    m.weights.add(a);
                } else if (p[1].startsWith("b")) {
                    m.biases.add(a[0]);
                } else {
                    throw new IOException("unknown matrix " + p[1]);
                }
            } else {
                m.keys.put(p[0], p.length > 1 ? p[1] : "");
            }
        }
        m.kind = m.keys.get("kind");
        if ("mlp".equals(m.kind)) {
            m.hiddenAct = m.keys.get("hidden_activation");
            m.outputAct = m.keys.get("output_activation");
            m.actA = m.num("act_a");
            m.actB = m.num("act_b");
        } else if (!"qtable".equals(m.kind) || m.q == null) {
            throw new IOException("policy kind must be qtable (with matrix q) or mlp, got " + m.kind);
        }
        return m;
    }

    double num(String key) {
        String v = keys.get(key);
        if (v == null) {
            throw new IllegalArgumentException("policy file lacks " + key);
        }
        return Double.parseDouble(v);
    }

    public int stepTurns() {
        return (int) num("step_turns");
    }

    /** Angle in [0, 2pi) (Robocode Utils.normalAbsoluteAngle, numpy mod semantics). */
    static double absAngle(double a) {
        double r = a - TWO_PI * Math.floor(a / TWO_PI);
        return r >= TWO_PI ? 0.0 : r;
    }

    /** Angle in [-pi, pi) as (a + pi) mod 2pi - pi. */
    static double relAngle(double a) {
        double s = a + Math.PI;
        return s - TWO_PI * Math.floor(s / TWO_PI) - Math.PI;
    }

    /** Index of the nearest enemy in ex/ey (first of equals), -1 if none. */
    static int nearest(double x, double y, double[] ex, double[] ey) {
        int best = -1;
        double bestD = Double.POSITIVE_INFINITY;
        for (int i = 0; i < ex.length; i++) {
            double dx = ex[i] - x;
            double dy = ey[i] - y;
            double d2 = dx * dx + dy * dy;
            if (d2 < bestD) {
                bestD = d2;
                best = i;
            }
        }
        return best;
    }

    double maxDistance(double width, double height) {
        double d = num("max_distance");
        return d > 0 ? d : Math.hypot(width, height);
    }

    /** The paper's discrete state 0..319 (confront.arena.observe.discrete_state). */
    int state(double x, double y, double heading, int t, double[] ex, double[] ey, double dmax) {
        double rel = 0.0;
        double dist = 0.0;
        if (t >= 0) {
            dist = Math.hypot(ex[t] - x, ey[t] - y);
            rel = absAngle(absAngle(Math.atan2(ex[t] - x, ey[t] - y)) - heading);
        }
        int relBin = Math.min((int) (absAngle(rel + TWO_PI / 8) / (TWO_PI / 4)), 3);
        int headBin = Math.min((int) (absAngle(heading) / (TWO_PI / 4)), 3);
        int distBin = (int) Math.max(0, Math.min(19, Math.floor(dist * (20 / dmax))));
        return (relBin * 4 + headBin) * 20 + distBin;
    }

    /** Continuous features (float32 like the Python side), see confront.arena.observe.features. */
    double[] features(double x, double y, double heading, double energy, int t, double[] ex, double[] ey,
                      double[] eEnergy, double dmax, double width, double height) {
        double rel = 0.0;
        double dist = 0.0;
        if (t >= 0) {
            dist = Math.hypot(ex[t] - x, ey[t] - y);
            rel = absAngle(absAngle(Math.atan2(ex[t] - x, ey[t] - y)) - heading);
        }
        boolean pos = num("include_position") != 0;
        double[] f = new double[pos ? 9 : 7];
        f[0] = Math.sin(rel);
        f[1] = Math.cos(rel);
        f[2] = Math.sin(heading);
        f[3] = Math.cos(heading);
        f[4] = Math.min(dist / dmax, 1.0);
        f[5] = energy / 100.0;
        f[6] = t >= 0 ? eEnergy[t] / 100.0 : 0.0;
        if (pos) {
            f[7] = x / width;
            f[8] = y / height;
        }
        for (int i = 0; i < f.length; i++) {
            f[i] = (float) f[i];
        }
        return f;
    }

    double activate(String act, double v) {
        switch (act) {
            case "bipolar": return actA * Math.tanh(actB * v / 2);  // Eq. 19: a(1-e^-bx)/(1+e^-bx)
            case "tanh": return Math.tanh(v);
            case "relu": return Math.max(0.0, v);
            case "linear": return v;
            default: throw new IllegalArgumentException("unknown activation " + act);
        }
    }

    /** Action values for one observation. */
    double[] values(int state, double[] features) {
        if (q != null) {
            return q[state];
        }
        double[] h = features;
        for (int l = 0; l < weights.size(); l++) {
            double[][] w = weights.get(l);
            double[] b = biases.get(l);
            double[] o = new double[w.length];
            String act = l == weights.size() - 1 ? outputAct : hiddenAct;
            for (int i = 0; i < w.length; i++) {
                double s = b[i];
                for (int j = 0; j < h.length; j++) {
                    s += w[i][j] * h[j];
                }
                o[i] = activate(act, s);
            }
            h = o;
        }
        return h;
    }

    /** The discrete state (0..319) for own position and heading and the enemies' last known positions: the row
     *  of a Q table that {@link #moveValues} reads. */
    public int moveState(double x, double y, double heading, double[] ex, double[] ey, double width, double height) {
        if (!"nearest".equals(keys.get("target"))) {
            throw new IllegalArgumentException("only target=nearest is exported");
        }
        return state(x, y, heading, nearest(x, y, ex, ey), ex, ey, maxDistance(width, height));
    }

    /** The four move values for own state and the enemies' last known positions/energies. */
    public double[] moveValues(double x, double y, double heading, double energy, double[] ex, double[] ey,
                               double[] ee, double width, double height) {
        if (!"nearest".equals(keys.get("target"))) {
            throw new IllegalArgumentException("only target=nearest is exported");
        }
        int t = nearest(x, y, ex, ey);
        double dmax = maxDistance(width, height);
        int s = state(x, y, heading, t, ex, ey, dmax);
        double[] in = null;
        if (q == null && "onehot".equals(keys.get("inputs"))) {
            in = new double[320];
            in[s] = 1.0;
        } else if (q == null) {
            in = features(x, y, heading, energy, t, ex, ey, ee, dmax, width, height);
        }
        return values(s, in);
    }

    /** Greedy move for own state and the enemies' last known positions/energies: the first maximum, or with
     *  "ties random" one of the maxima at random (Math.random: the engine's seed does not reach it). */
    public int act(double x, double y, double heading, double energy, double[] ex, double[] ey, double[] ee,
                   double width, double height) {
        double[] v = moveValues(x, y, heading, energy, ex, ey, ee, width, height);
        int best = 0;
        int equal = 1;
        boolean random = "random".equals(keys.get("ties"));
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

    /** (gun turn, radar turn, fire power) of the fixed controller (confront.arena.control). */
    public double[] gunRadar(double x, double y, double gunHeading, double radarHeading, double gunHeat,
                             double energy, double[] ex, double[] ey) {
        int t = nearest(x, y, ex, ey);
        if (t < 0) {
            return new double[] {Double.NaN, TWO_PI, 0.0};
        }
        double dx = ex[t] - x;
        double dy = ey[t] - y;
        double bearing = Math.atan2(dx, dy);
        double dist = Math.hypot(dx, dy);
        double gun = relAngle(bearing - gunHeading);
        double radar = relAngle(bearing - radarHeading);
        radar += Math.signum(radar) * num("radar_overshoot");
        boolean fire = Math.abs(gun) <= num("aim_tolerance") && gunHeat == 0 && energy > 0 && num("fire") != 0;
        double power = dist < num("near_distance") ? num("power_near")
                : dist < num("far_distance") ? num("power_mid") : num("power_far");
        return new double[] {gun, radar, fire ? power : 0.0};
    }
}
