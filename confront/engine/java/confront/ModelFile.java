package confront;

import java.io.BufferedReader;
import java.io.IOException;
import java.io.Reader;
import java.util.HashMap;
import java.util.LinkedHashMap;
import java.util.Map;

/**
 * The model file of an exported robot (no Robocode dependency), read by PolicyModel and TankModel: a header line
 * ("confront-policy 1", "confront-tank 1"), then "key value" lines (the value: the rest of the line), "#" comment
 * and empty lines, and "matrix NAME ROWS COLS" blocks of ROWS lines of COLS space-separated numbers. The files
 * are written by confront.engine.export and confront.engine.tank_export. A model takes its matrices by name
 * (the MLP's: {@link #mlp}) and then checks that none is left over.
 */
public final class ModelFile {
    final String what;  // "policy" or "tank policy", for the error messages
    final Map<String, String> keys = new HashMap<>();
    private final Map<String, double[][]> matrices = new LinkedHashMap<>();

    private ModelFile(String what) {
        this.what = what;
    }

    /** Reads a file whose first line is {@code header}; {@code what} names the file in error messages. */
    public static ModelFile read(Reader source, String header, String what) throws IOException {
        ModelFile m = new ModelFile(what);
        BufferedReader r = new BufferedReader(source);
        String first = r.readLine();
        if (first == null || !first.equals(header)) {
            throw new IOException("not a confront " + what + " file (version 1): " + first);
        }
        String line;
        while ((line = r.readLine()) != null) {
            if (line.isEmpty() || line.startsWith("#")) {
                continue;
            }
            String[] p = line.split(" ");
            if (p[0].equals("matrix")) {
                if (m.matrices.put(p[1], matrix(r, p[1], Integer.parseInt(p[2]), Integer.parseInt(p[3]))) != null) {
                    throw new IOException("matrix " + p[1] + " given twice");
                }
            } else {
                int sp = line.indexOf(' ');
                m.keys.put(sp < 0 ? line : line.substring(0, sp), sp < 0 ? "" : line.substring(sp + 1));
            }
        }
        return m;
    }

    private static double[][] matrix(BufferedReader r, String name, int rows, int cols) throws IOException {
        double[][] a = new double[rows][cols];
        for (int i = 0; i < rows; i++) {
            String row = r.readLine();
            String[] v = row == null ? new String[0] : row.split(" ");
            if (v.length != cols) {
                throw new IOException("matrix " + name + " row " + i + " has " + v.length + " values");
            }
            for (int j = 0; j < cols; j++) {
                a[i][j] = Double.parseDouble(v[j]);
            }
        }
        return a;
    }

    /** The value of a key, or {@code otherwise} when the file has none. */
    String text(String key, String otherwise) {
        return keys.getOrDefault(key, otherwise);
    }

    /** The value of a key that must be one of {@code allowed}, else {@code otherwise} when the file has none. */
    String choice(String key, String otherwise, String... allowed) throws IOException {
        String v = keys.getOrDefault(key, otherwise);
        for (String a : allowed) {
            if (a.equals(v)) {
                return v;
            }
        }
        throw new IOException(key + " must be " + String.join(" or ", allowed) + ", got " + v);
    }

    double num(String key) {
        String v = keys.get(key);
        if (v == null) {
            throw new IllegalArgumentException(what + " file lacks " + key);
        }
        return Double.parseDouble(v.trim());
    }

    double[] list(String key) {
        String v = keys.get(key);
        if (v == null || v.trim().isEmpty()) {
            throw new IllegalArgumentException(what + " file lacks " + key);
        }
        return numbers(v);
    }

    /** Space-separated numbers (none for a blank text). */
    static double[] numbers(String s) {
        String t = s.trim();
        if (t.isEmpty()) {
            return new double[0];
        }
        String[] p = t.split(" ");
        double[] a = new double[p.length];
        for (int i = 0; i < p.length; i++) {
            a[i] = Double.parseDouble(p[i]);
        }
        return a;
    }

    /** Takes the matrix out of the file (null when it has none). */
    double[][] take(String name) {
        return matrices.remove(name);
    }

    /** Fails on a matrix no model part has taken. */
    void allTaken() throws IOException {
        for (Map.Entry<String, double[][]> e : matrices.entrySet()) {
            double[][] a = e.getValue();
            throw new IOException("unexpected matrix " + e.getKey() + " " + a.length + "x"
                    + (a.length > 0 ? a[0].length : 0));
        }
    }

    /**
     * The MLP of matrices w0, b0, w1, b1, ... (each bias one row) with the hidden layers' and the output layer's
     * activation: bipolar (Eq. 19: a (1 - e^-bx) / (1 + e^-bx), a and b from actA, actB), tanh, relu or linear.
     */
    Mlp mlp(String hidden, String output, double actA, double actB) throws IOException {
        Mlp n = new Mlp(hidden, output, actA, actB);
        for (int l = 0; matrices.containsKey("w" + l); l++) {
            double[][] b = take("b" + l);
            if (b == null || b.length != 1) {
                throw new IOException("the MLP needs matrices w0, b0, w1, b1, ... (b" + l + ": one row)");
            }
            n.weights.add(take("w" + l));
            n.biases.add(b[0]);
        }
        return n;
    }
}
