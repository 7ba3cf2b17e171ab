package confront;

import java.io.IOException;
import java.util.ArrayList;
import java.util.List;

/**
 * A multilayer perceptron of an exported model (ModelFile.mlp): weights (out, in) and biases per layer, one
 * activation for the hidden layers and one for the last (bipolar, tanh, relu or linear).
 */
public final class Mlp {
    final List<double[][]> weights = new ArrayList<>();
    final List<double[]> biases = new ArrayList<>();
    final String hidden;
    final String output;
    final double actA;
    final double actB;

    Mlp(String hidden, String output, double actA, double actB) {
        this.hidden = hidden;
        this.output = output;
        this.actA = actA;
        this.actB = actB;
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

    /** The outputs for the inputs {@code in}: per layer act(b + W h), summed in input order. */
    double[] forward(double[] in) {
        double[] h = in;
        for (int l = 0; l < weights.size(); l++) {
            double[][] w = weights.get(l);
            double[] b = biases.get(l);
            double[] o = new double[w.length];
            String act = l == weights.size() - 1 ? output : hidden;
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

    /** Fails unless there is a layer and the layers chain from {@code in} inputs to {@code out} outputs. */
    void check(int in, int out) throws IOException {
        if (weights.isEmpty()) {
            throw new IOException("the MLP needs matrices w0, b0, w1, b1, ... (got none)");
        }
        int n = in;
        for (int l = 0; l < weights.size(); l++) {
            double[][] w = weights.get(l);
            if (w.length == 0 || w[0].length != n || biases.get(l).length != w.length) {
                throw new IOException("layer " + l + " does not chain from " + n + " inputs");
            }
            n = w.length;
        }
        if (n != out) {
            throw new IOException("the MLP outputs " + n + " values, " + out + " are needed");
        }
    }
}
