package confront;

import java.io.BufferedReader;
import java.io.FileReader;
import java.io.InputStreamReader;

/**
 * Prints the exported policy's decisions for bridge observation lines read from stdin, one output line
 * per input: "ACTION GUN RADAR FIRE STATE" (STATE: the paper's discrete state 0..319). Arguments:
 * POLICY_FILE WIDTH HEIGHT.
 */
public final class PolicyCheck {
    public static void main(String[] args) throws Exception {
        PolicyModel m;
        try (FileReader f = new FileReader(args[0])) {
            m = PolicyModel.read(f);
        }
        double width = Double.parseDouble(args[1]);
        double height = Double.parseDouble(args[2]);
        BufferedReader in = new BufferedReader(new InputStreamReader(System.in));
        StringBuilder out = new StringBuilder();
        String line;
        while ((line = in.readLine()) != null) {
            String[] parts = line.split("\t", -1);
            String[] h = parts[0].split(" ");
            double x = Double.parseDouble(h[3]);
            double y = Double.parseDouble(h[4]);
            double heading = Double.parseDouble(h[5]);
            double gunH = Double.parseDouble(h[6]);
            double radarH = Double.parseDouble(h[7]);
            double energy = Double.parseDouble(h[9]);
            double heat = Double.parseDouble(h[10]);
            String[] scans = parts[1].isEmpty() ? new String[0] : parts[1].split("\\|");
            double[][] enemies = new double[scans.length][];
            int n = 0;
            for (String s : scans) {
                String[] f = s.split(";");
                if (f[2].equals("1")) {
                    continue;
                }
                enemies[n++] = new double[] {Double.parseDouble(f[8]), Double.parseDouble(f[9]),
                        Double.parseDouble(f[7])};
            }
            enemies = java.util.Arrays.copyOf(enemies, n);
            int a = m.act(x, y, heading, energy, enemies, width, height);
            double[] g = m.gunRadar(x, y, gunH, radarH, heat, energy, enemies);
            int state = m.moveState(x, y, heading, enemies, width, height);
            out.append(a).append(' ').append(g[0]).append(' ').append(g[1]).append(' ').append(g[2]).append(' ')
                    .append(state).append('\n');
        }
        System.out.print(out);
    }
}
