package confront;

import java.io.BufferedReader;
import java.io.FileReader;
import java.io.InputStreamReader;

/**
 * Prints TankModel's answers for request lines read from stdin (tab-separated sections, rows separated by
 * "|", values by spaces), one output line per request. Argument: TANK_POLICY_FILE.
 *
 * <ul>
 * <li>"V own enemies mates", own = x y heading velocity energy gunHeat enemiesAlive enemiesStart matesAlive
 * matesStart time width height; prints the view, then "|" and the slots.</li>
 * <li>"A view"; prints the joint action, then "|" and the logits.</li>
 * <li>"S view draws" (one uniform draw per head); prints the sampled joint action.</li>
 * <li>"C own enemies", own = x y heading gunHeading radarHeading gunHeat energy power chosen turn lead time
 * width height (lead: 0 none, 1 linear, 2 circular); prints gun radar fire target bodyTurn.</li>
 * <li>"R seen prevHeading prevTime heading time" (seen 0: no previous scan); prints the turn rate.</li>
 * </ul>
 */
public final class TankCheck {
    static double[] nums(String s) {
        return ModelFile.numbers(s);
    }

    static double[][] rows(String s) {
        if (s.trim().isEmpty()) {
            return new double[0][];
        }
        String[] p = s.split("\\|");
        double[][] a = new double[p.length][];
        for (int i = 0; i < p.length; i++) {
            a[i] = nums(p[i]);
        }
        return a;
    }

    public static void main(String[] args) throws Exception {
        TankModel m;
        try (FileReader f = new FileReader(args[0])) {
            m = TankModel.read(f);
        }
        BufferedReader in = new BufferedReader(new InputStreamReader(System.in));
        StringBuilder out = new StringBuilder();
        String line;
        while ((line = in.readLine()) != null) {
            String[] parts = line.split("\t", -1);
            switch (parts[0]) {
                case "V": {
                    double[] o = nums(parts[1]);
                    int[] slots = new int[m.enemySlots];
                    double[] v = m.view(o[0], o[1], o[2], o[3], o[4], o[5], (int) o[6], (int) o[7], (int) o[8],
                            (int) o[9], rows(parts[2]), rows(parts[3]), o[10], o[11], o[12], slots);
                    for (double x : v) {
                        out.append(x).append(' ');
                    }
                    out.append('|');
                    for (int s : slots) {
                        out.append(' ').append(s);
                    }
                    break;
                }
                case "A": {
                    double[] v = nums(parts[1]);
                    out.append(m.act(v)).append(" |");
                    for (double z : m.logits(v)) {
                        out.append(' ').append(z);
                    }
                    break;
                }
                case "S": {
                    out.append(m.sample(nums(parts[1]), nums(parts[2])));
                    break;
                }
                case "C": {
                    double[] o = nums(parts[1]);
                    double[][] en = rows(parts[2]);
                    int tgt = TankModel.target(o[0], o[1], en, (int) o[8]);
                    double[] g = m.control(o[0], o[1], o[3], o[4], o[5], o[6], en, tgt, o[7], (int) o[10], o[11],
                            o[12], o[13]);
                    out.append(g[0]).append(' ').append(g[1]).append(' ').append(g[2]).append(' ').append(tgt)
                            .append(' ').append(m.bodyTurn(o[0], o[1], o[2], en, tgt, o[9]));
                    break;
                }
                case "R": {
                    double[] o = nums(parts[1]);
                    double[] prev = o[0] != 0 ? new double[] {0, 0, 0, o[1], 0, 0, o[2], 0} : null;
                    out.append(TankModel.turnRate(prev, o[3], o[4]));
                    break;
                }
                default:
                    throw new IllegalArgumentException("unknown request " + parts[0]);
            }
            out.append('\n');
        }
        System.out.print(out);
    }
}
