package confront;

import java.io.BufferedReader;
import java.io.IOException;
import java.io.InputStreamReader;
import java.io.OutputStream;
import java.io.StringReader;
import java.net.InetAddress;
import java.net.InetSocketAddress;
import java.net.Socket;
import java.util.SplittableRandom;
import java.nio.charset.StandardCharsets;
import java.util.ArrayDeque;
import java.util.HashMap;
import java.util.LinkedHashMap;
import java.util.Map;

import robocode.BulletHitEvent;
import robocode.DeathEvent;
import robocode.HitByBulletEvent;
import robocode.HitRobotEvent;
import robocode.HitWallEvent;
import robocode.RobotDeathEvent;
import robocode.RoundEndedEvent;
import robocode.ScannedRobotEvent;
import robocode.TeamRobot;
import robocode.WinEvent;
import robocode.util.Utils;

/**
 * A tank that takes its decisions from a Python policy over a loopback TCP socket.
 *
 * Settings come from JVM system properties (the engine runs with -DNOSECURITY=true so that robots may use
 * sockets): confront.bridge.port, confront.bridge.timeoutMs; the token from the engine's environment variable
 * CONFRONT_BRIDGE_TOKEN (a command line is visible to every local user, an environment only to its own). Protocol version 2
 * (format in confront/engine/bridge.py), one line per message: the robot sends a JSON "hello" once per round
 * and Python answers "OK 2 EVERY LEAD HISTORY N" plus N "key value" lines of the fixed gun/radar controller
 * (N = 0: none); with HISTORY = 1 the robot records every turn's energies and sends them with the next message.
 * The robot then asks for decisions in turns 1, 1 + EVERY, 1 + 2 EVERY, ...: it sends the "O ..." observation
 * LEAD turns before such a turn (0: in it; the first of a round always in turn 1) and reads the answer in it,
 * so with LEAD > 0 Python decides while the engine plays on (from a state LEAD turns old); "E ..." at death
 * or round end; Python answers each observation with "A TURN AHEAD TURN GUN RADAR FIRE" (radians,
 * + clockwise; "NaN" keeps the current remaining value; fire 0 = no shot). Between decisions the commands keep
 * running and, with a controller, PolicyModel's gun/radar controller aims and fires every turn (its commands
 * replace the answer's gun, radar and fire), so no round trip is needed there. Any missing, late or malformed
 * answer switches the robot to a built-in behaviour for the rest of the round and prints
 * "CONFRONT bridge-failed REASON" for the runner to report. The "E" line carries the round's statistics:
 * decisions, their round-trip times, turns played and the robot's own work time outside execute().
 *
 * Acting mode (the hello reply's 7th field M > 0, followed by "acting EXPLORE PARAM SEED MAX_LAG WAIT FIXED" and
 * a policy file): the robot picks its moves itself from its own copy of the Q table (PolicyModel, as PolicyBot
 * does, with the learner's exploration: first maximum, random-tie greedy, Boltzmann or epsilon-greedy) and sends
 * each observation with "MOVE;BEHIND;AHEAD" appended (the unacknowledged observations that counted for the move and
 * the others), never waiting for an answer. Python acknowledges each observation
 * ("K TURN") and sends every change of the policy to every acting robot ("Q STATE V0 V1 V2 V3", "X PARAM FIXED");
 * the robot reads them without blocking at its decision turns, and waits (at most its timeout) only when MAX_LAG
 * of its observations are unacknowledged that count: with WAIT = "all" every one, with WAIT = "row" (a learner's
 * robots) only those whose update could change the move it is about to draw, i.e. whose learned step starts at
 * the state it decides in now (Python learns, at observation k, the step from the robot's decision k - 1), or any
 * update while the exploration parameter may still change (FIXED 0). The others change rows this move does not
 * read, so the move is the one a copy with every update would draw. At most 1000 observations stay
 * unacknowledged. A closed connection or a bad line makes it fall back as above.
 */
public class BridgeBot extends TeamRobot {
    static final int VERSION = 2;
    private Socket socket;
    private BufferedReader in;
    private OutputStream out2;
    private boolean failed;
    private boolean finished;
    private int every = 1;
    private int lead;
    private long nextDecision = 1;
    private boolean pending;
    private long requestNanos;
    private boolean keepHistory;
    private PolicyModel controller;
    // acting mode: the robot's own copy of the policy, kept current by Python's Q / X lines
    private PolicyModel acting;
    private String explore = "first";
    private double param;
    private SplittableRandom random;
    private int maxLag;
    private boolean waitAll = true;  // WAIT "all": every unacknowledged observation counts; "row": see above
    private boolean paramFixed;  // the exploration parameter no longer changes (FIXED 1)
    private int lastState = -1;  // the state of this robot's previous decision in this round (-1: none yet)
    // unacknowledged observations: turn, and the Q row Python learns when it takes them in (-1: none)
    private final ArrayDeque<long[]> unacked = new ArrayDeque<>();
    static final int MAX_UNACKED = 1000;
    // per turn since the last message: TIME;OWN_ENERGY;TARGET;TARGET_PREVIOUS_ENERGY;TARGET_ENERGY, joined by "|"
    private final StringBuilder history = new StringBuilder();
    private Map<String, Double> lastEnergies = new HashMap<>();
    private long rttN;
    private long rttSum;
    private long rttSlow;
    private long workNanos;
    private long turnsPlayed;
    // latest scan per robot: time, teammate (0/1), bearing, distance, heading, velocity, energy, x, y
    private final Map<String, double[]> scans = new LinkedHashMap<>();
    // enemies only, as PolicyBot keeps them: x, y, energy
    private final Map<String, double[]> enemies = new LinkedHashMap<>();
    private final StringBuilder events = new StringBuilder();
    private double enemyBearing = Double.NaN;
    private long lastScan = -100;

    @Override
    public void run() {
        // the engine waits for this robot's first action; connecting first delays it past the engine's wait
        RobotParts.start(this);
        connect();
        while (true) {
            long t0 = System.nanoTime();
            long turn = getTime() + 1;  // the commands set now take effect in this engine turn
            if (keepHistory && !failed && !finished) {
                record();
            }
            if (!failed && !finished) {
                try {
                    if (acting != null) {
                        if (turn >= nextDecision) {
                            while (nextDecision < turn) {
                                nextDecision += every;  // a skipped turn passed a decision turn: take the next one
                            }
                            actSelf(turn);
                            nextDecision += every;
                        }
                    } else if (!pending) {
                        while (nextDecision < turn) {
                            nextDecision += every;  // a skipped turn passed a decision turn: take the next one
                        }
                        if (turn >= nextDecision - lead) {
                            request(nextDecision);  // "lead" turns ahead: Python works while the engine runs
                            pending = true;
                        }
                    }
                    if (acting == null && pending && turn >= nextDecision) {
                        receive(nextDecision);  // late only when a skipped turn passed the decision turn
                        pending = false;
                        nextDecision += every;
                    }
                } catch (IOException | RuntimeException e) {
                    fail(e.getClass().getSimpleName() + ": " + e.getMessage());
                }
            }
            if (failed) {
                fallback();
            } else if (controller != null) {
                control();
            }
            turnsPlayed++;
            workNanos += System.nanoTime() - t0;
            execute();
        }
    }

    private void connect() {
        String port = System.getProperty("confront.bridge.port");
        if (port == null) {
            fail("no confront.bridge.port property");
            return;
        }
        try {
            int timeout = Integer.parseInt(System.getProperty("confront.bridge.timeoutMs", "200"));
            socket = new Socket();
            socket.setTcpNoDelay(true);
            socket.connect(new InetSocketAddress(InetAddress.getLoopbackAddress(), Integer.parseInt(port)), timeout);
            socket.setSoTimeout(timeout);
            in = new BufferedReader(new InputStreamReader(socket.getInputStream(), StandardCharsets.UTF_8));
            out2 = socket.getOutputStream();
            send("{\"v\":" + VERSION + ",\"type\":\"hello\",\"token\":" + str(token())
                    + ",\"name\":" + str(getName()) + ",\"team\":" + str(teamName())
                    + ",\"round\":" + getRoundNum() + ",\"rounds\":" + getNumRounds()
                    + ",\"width\":" + getBattleFieldWidth() + ",\"height\":" + getBattleFieldHeight() + "}");
            String reply = in.readLine();
            String[] p = reply == null ? new String[0] : reply.split(" ");
            if ((p.length != 6 && p.length != 7) || !p[0].equals("OK") || !p[1].equals(String.valueOf(VERSION))) {
                fail("bad hello reply " + reply);
                return;
            }
            every = Integer.parseInt(p[2]);
            lead = Integer.parseInt(p[3]);
            keepHistory = p[4].equals("1");
            int n = Integer.parseInt(p[5]);
            int m = p.length == 7 ? Integer.parseInt(p[6]) : 0;
            if (every < 1 || lead < 0 || lead >= every || !(p[4].equals("0") || keepHistory) || n < 0 || n > 100
                    || m < 0 || m > 1000000 || (m > 0 && (n == 0 || lead != 0))) {
                fail("bad hello reply " + reply);
                return;
            }
            if (n > 0) {
                controller = controllerModel(n);
            }
            if (m > 0) {
                actingModel(m);
            }
        } catch (IOException | RuntimeException e) {
            fail("connect: " + e.getClass().getSimpleName() + ": " + e.getMessage());
        }
    }

    /** The bridge token from the environment ("" if none: the server then refuses the hello). */
    private static String token() {
        String t = System.getenv("CONFRONT_BRIDGE_TOKEN");
        return t == null ? "" : t;
    }

    /** The controller's "key value" lines (confront.engine.bridge.controller_lines) as a PolicyModel. */
    private PolicyModel controllerModel(int n) throws IOException {
        StringBuilder text = new StringBuilder("confront-policy 1\nkind qtable\nstep_turns ").append(every)
                .append("\ntarget nearest\nmax_distance 0.0\ninclude_position 0\n");
        for (int i = 0; i < n; i++) {
            String line = in.readLine();
            if (line == null || line.split(" ").length != 2) {
                throw new IOException("bad controller line " + line);
            }
            text.append(line).append('\n');
        }
        // PolicyModel reads a policy file; the controller needs no values, so a 1 x 4 table stands in
        return PolicyModel.read(new StringReader(text.append("matrix q 1 4\n0 0 0 0\n").toString()));
    }

    /** The "acting EXPLORE PARAM SEED MAX_LAG WAIT FIXED" line and the policy file of the robot's own copy of the
     *  policy. */
    private void actingModel(int m) throws IOException {
        String head = in.readLine();
        String[] p = head == null ? new String[0] : head.split(" ");
        if (p.length != 7 || !p[0].equals("acting")
                || !(p[1].equals("first") || p[1].equals("greedy") || p[1].equals("boltzmann") || p[1].equals("egreedy"))
                || !(p[5].equals("all") || p[5].equals("row")) || !(p[6].equals("0") || p[6].equals("1"))) {
            throw new IOException("bad acting line " + head);
        }
        explore = p[1];
        param = param(p[2]);
        random = new SplittableRandom(Long.parseLong(p[3]));
        maxLag = Integer.parseInt(p[4]);
        waitAll = p[5].equals("all");
        paramFixed = p[6].equals("1");
        if (maxLag < 1 || maxLag > MAX_UNACKED) {
            throw new IOException("bad acting line " + head);
        }
        StringBuilder text = new StringBuilder();
        for (int i = 1; i < m; i++) {
            String line = in.readLine();
            if (line == null) {
                throw new IOException("policy file cut short");
            }
            text.append(line).append('\n');
        }
        acting = PolicyModel.read(new StringReader(text.toString()));
        if (acting.q == null) {
            throw new IOException("a robot that acts itself needs a Q table");
        }
    }

    /** The exploration parameter: a temperature > 0 (Boltzmann) or a threshold in [0, 1]. */
    private double param(String text) {
        double v = finite(text);
        if (explore.equals("boltzmann") ? !(v > 0) : (v < 0 || v > 1)) {
            throw new IllegalArgumentException("exploration parameter " + text + " out of range for " + explore);
        }
        return v;
    }

    private static double finite(String text) {
        double v = Double.parseDouble(text);
        if (Double.isNaN(v) || Double.isInfinite(v)) {
            throw new IllegalArgumentException("non-finite value " + text);
        }
        return v;
    }

    /**
     * A decision turn when acting: take the updates that arrived (waiting only when maxLag unacknowledged
     * observations count for this move), pick the move from the own copy of the policy, set it, and send the
     * observation with it.
     */
    private void actSelf(long turn) throws IOException {
        long t0 = System.nanoTime();
        while (in.ready()) {
            update(in.readLine());
        }
        int s = acting.moveState(getX(), getY(), getHeadingRadians(), enemies.values().toArray(new double[0][]),
                getBattleFieldWidth(), getBattleFieldHeight());
        while (unacked.size() >= MAX_UNACKED || behind(s) >= maxLag) {
            update(in.readLine());  // at most the socket's timeout, then the robot falls back
        }
        long waited = System.nanoTime() - t0;
        int a = choose(acting.q[s]);  // PolicyModel.moveValues of a Q table: the row of state s
        double[] mv = acting.move(a);
        setAhead(mv[0]);
        setTurnRightRadians(mv[1]);
        int counted = behind(s);
        request(turn, a + ";" + counted + ";" + (unacked.size() - counted));
        unacked.addLast(new long[] {turn, lastState});
        lastState = s;
        long dt = waited + requestNanos;  // held up by Python: the wait for acknowledgements and the send
        rttN++;
        rttSum += dt;
        if (dt > 1000000) {
            rttSlow++;
        }
    }

    /** Unacknowledged observations that count for a move drawn in state s (WAIT above). */
    private int behind(int s) {
        if (waitAll) {
            return unacked.size();
        }
        int k = 0;
        for (long[] u : unacked) {
            if (u[1] >= 0 && (u[1] == s || !paramFixed)) {
                k++;  // its update changes row s, or may change the exploration parameter
            }
        }
        return k;
    }

    /** One line from Python while acting: K (acknowledgement), Q (a Q-table row), X (exploration parameter). */
    private void update(String line) throws IOException {
        if (line == null) {
            throw new IOException("python side closed the connection");
        }
        String[] p = line.split(" ");
        if (p[0].equals("K") && p.length == 2) {
            long[] u = unacked.pollFirst();
            if (u == null || u[0] != Long.parseLong(p[1])) {
                throw new IllegalArgumentException("acknowledgement '" + line + "' out of order");
            }
        } else if (p[0].equals("Q") && p.length == 6) {
            int s = Integer.parseInt(p[1]);
            if (s < 0 || s >= acting.q.length) {
                throw new IllegalArgumentException("Q row " + s + " outside the table");
            }
            double[] row = new double[4];
            for (int j = 0; j < 4; j++) {
                row[j] = finite(p[j + 2]);
            }
            acting.q[s] = row;
        } else if (p[0].equals("X") && p.length == 3 && (p[2].equals("0") || p[2].equals("1"))) {
            param = param(p[1]);
            paramFixed = p[2].equals("1");
        } else {
            throw new IllegalArgumentException("bad update line '" + line + "'");
        }
    }

    /** The move from its values: first maximum, a maximum at random, softmax at temperature param, or
     *  epsilon-greedy with exploitation threshold param (confront.learning.exploration). */
    private int choose(double[] v) {
        switch (explore) {
            case "greedy":
                return randomMax(v);
            case "egreedy":
                return random.nextDouble() < param ? randomMax(v) : random.nextInt(v.length);
            case "boltzmann": {
                double m = Double.NEGATIVE_INFINITY;
                for (double x : v) {
                    m = Math.max(m, x / param);
                }
                double[] cdf = new double[v.length];
                double sum = 0.0;
                for (int i = 0; i < v.length; i++) {
                    sum += Math.exp(v[i] / param - m);
                    cdf[i] = sum;
                }
                double u = random.nextDouble() * sum;
                int k = 0;
                while (k < v.length && cdf[k] <= u) {
                    k++;
                }
                return Math.min(k, v.length - 1);
            }
            default: {
                int best = 0;
                for (int i = 1; i < v.length; i++) {
                    if (v[i] > v[best]) {
                        best = i;
                    }
                }
                return best;
            }
        }
    }

    private int randomMax(double[] v) {
        double m = Double.NEGATIVE_INFINITY;
        for (double x : v) {
            m = Math.max(m, x);
        }
        int count = 0;
        int pick = 0;
        for (int i = 0; i < v.length; i++) {
            if (v[i] == m && random.nextInt(++count) == 0) {
                pick = i;  // reservoir sampling: each maximum with equal probability
            }
        }
        return pick;
    }

    private String teamName() {
        String[] mates = getTeammates();
        return mates == null ? "" : String.join(";", mates);
    }

    /** Send the observation for decision turn ``turn`` (now, or ``lead`` turns before it). */
    private void request(long turn) throws IOException {
        request(turn, null);
    }

    /** Send the observation for ``turn``; ``move``: the move this robot took itself (acting), else null. */
    private void request(long turn, String move) throws IOException {
        StringBuilder b = new StringBuilder(256);
        b.append("O ").append(getRoundNum()).append(' ').append(turn)
                .append(' ').append(getX()).append(' ').append(getY())
                .append(' ').append(getHeadingRadians()).append(' ').append(getGunHeadingRadians())
                .append(' ').append(getRadarHeadingRadians()).append(' ').append(getVelocity())
                .append(' ').append(getEnergy()).append(' ').append(getGunHeat())
                .append(' ').append(getOthers()).append(' ').append(getDistanceRemaining()).append('\t');
        boolean first = true;
        for (Map.Entry<String, double[]> e : scans.entrySet()) {
            double[] s = e.getValue();
            if (!first) {
                b.append('|');
            }
            first = false;
            b.append(e.getKey()).append(';').append((long) s[0]).append(';').append((int) s[1]);
            for (int i = 2; i < s.length; i++) {
                b.append(';').append(s[i]);
            }
        }
        b.append("\t[").append(events).append("]\t").append(history);
        if (move != null) {
            b.append('\t').append(move);
        }
        b.append('\n');
        events.setLength(0);
        history.setLength(0);
        long t0 = System.nanoTime();
        out2.write(b.toString().getBytes(StandardCharsets.UTF_8));
        out2.flush();
        requestNanos = System.nanoTime() - t0;
    }

    /** Read and apply the answer for ``turn``; times how long this robot was held up (sending and waiting). */
    private void receive(long turn) throws IOException {
        long t0 = System.nanoTime();
        String line = in.readLine();
        long dt = System.nanoTime() - t0 + requestNanos;
        rttN++;
        rttSum += dt;
        if (dt > 1000000) {
            rttSlow++;
        }
        if (line == null) {
            throw new IOException("python side closed the connection");
        }
        String[] p = line.trim().split(" ");
        if (p.length != 7 || !p[0].equals("A") || Long.parseLong(p[1]) != turn) {
            throw new IllegalArgumentException("bad action line '" + line + "' for turn " + turn);
        }
        double[] a = new double[5];
        for (int i = 0; i < 5; i++) {
            a[i] = Double.parseDouble(p[i + 2]);
            if (Double.isInfinite(a[i])) {
                throw new IllegalArgumentException("infinite value in '" + line + "'");
            }
        }
        if (!Double.isNaN(a[0])) {
            setAhead(a[0]);
        }
        if (!Double.isNaN(a[1])) {
            setTurnRightRadians(a[1]);
        }
        if (controller != null) {
            return;  // the controller sets gun, radar and fire
        }
        if (!Double.isNaN(a[2])) {
            setTurnGunRightRadians(a[2]);
        }
        if (!Double.isNaN(a[3])) {
            setTurnRadarRightRadians(a[3]);
        }
        if (!Double.isNaN(a[4]) && a[4] > 0) {
            setFire(a[4]);
        }
    }

    /**
     * This turn's own energy and its target's (the nearest enemy by last scans, as the controller picks it)
     * energy now and at the previous record, for the paper's per-turn reward (Eq. 35) between decisions.
     */
    private void record() {
        String[] names = enemies.keySet().toArray(new String[0]);
        Map<String, Double> now = new HashMap<>();
        for (Map.Entry<String, double[]> e : enemies.entrySet()) {
            now.put(e.getKey(), e.getValue()[2]);
        }
        int t = Aim.nearest(getX(), getY(), enemies.values().toArray(new double[0][]));
        if (history.length() > 0) {
            history.append('|');
        }
        history.append(getTime()).append(';').append(getEnergy()).append(';');
        if (t >= 0) {
            double e = now.get(names[t]);
            history.append(names[t]).append(';').append(lastEnergies.getOrDefault(names[t], e)).append(';').append(e);
        } else {
            history.append(";0.0;0.0");
        }
        lastEnergies = now;
    }

    /** The fixed gun/radar controller on the enemies' last scans, as PolicyBot runs it every turn. */
    private void control() {
        RobotParts.command(this, controller.gunRadar(getX(), getY(), getGunHeadingRadians(),
                getRadarHeadingRadians(), getGunHeat(), getEnergy(), enemies.values().toArray(new double[0][])));
    }

    private void send(String line) throws IOException {
        out2.write((line + "\n").getBytes(StandardCharsets.UTF_8));
        out2.flush();
    }

    private void fail(String reason) {
        if (!failed) {
            failed = true;
            out.println("CONFRONT bridge-failed round=" + getRoundNum() + " turn=" + getTime() + " " + reason);
            close();
        }
    }

    private void close() {
        try {
            if (socket != null) {
                socket.close();
            }
        } catch (IOException e) {
            // already closed
        }
    }

    /** Built-in behaviour when Python is gone: keep the radar spinning, weave, shoot at what is seen. */
    private void fallback() {
        setTurnRadarRightRadians(Double.POSITIVE_INFINITY);
        long t = getTime();
        if (getDistanceRemaining() == 0) {
            setAhead((t / 25) % 2 == 0 ? 120 : -120);
        }
        if (t - lastScan < 5 && !Double.isNaN(enemyBearing)) {
            double aim = Utils.normalRelativeAngle(getHeadingRadians() + enemyBearing - getGunHeadingRadians());
            setTurnGunRightRadians(aim);
            setTurnRightRadians(Utils.normalRelativeAngle(enemyBearing + Math.PI / 2));
            if (Math.abs(aim) < 0.05 && getGunHeat() == 0 && getEnergy() > 1) {
                setFire(1.0);
            }
        }
    }

    private void event(String json) {
        if (events.length() > 0) {
            events.append(',');
        }
        events.append(json);
    }

    @Override
    public void onScannedRobot(ScannedRobotEvent e) {
        double abs = getHeadingRadians() + e.getBearingRadians();
        boolean mate = isTeammate(e.getName());
        double x = getX() + e.getDistance() * Math.sin(abs);
        double y = getY() + e.getDistance() * Math.cos(abs);
        if (!mate) {
            enemyBearing = e.getBearingRadians();
            lastScan = e.getTime();
            enemies.put(e.getName(), new double[] {x, y, e.getEnergy()});
        }
        scans.put(e.getName(), new double[] {e.getTime(), mate ? 1 : 0, e.getBearingRadians(), e.getDistance(),
                e.getHeadingRadians(), e.getVelocity(), e.getEnergy(), x, y});
    }

    @Override
    public void onRobotDeath(RobotDeathEvent e) {
        scans.remove(e.getName());
        enemies.remove(e.getName());
        event("{\"type\":\"robot_death\",\"name\":" + str(e.getName()) + "}");
    }

    @Override
    public void onHitWall(HitWallEvent e) {
        event("{\"type\":\"hit_wall\"}");
    }

    @Override
    public void onHitRobot(HitRobotEvent e) {
        event("{\"type\":\"hit_robot\",\"name\":" + str(e.getName()) + ",\"my_fault\":" + e.isMyFault() + "}");
    }

    @Override
    public void onHitByBullet(HitByBulletEvent e) {
        event("{\"type\":\"hit_by_bullet\",\"name\":" + str(e.getName()) + ",\"power\":" + e.getPower() + "}");
    }

    @Override
    public void onBulletHit(BulletHitEvent e) {
        event("{\"type\":\"bullet_hit\",\"name\":" + str(e.getName()) + ",\"power\":" + e.getBullet().getPower()
                + "}");
    }

    private void finish(String how) {
        if (finished) {
            return;
        }
        finished = true;
        if (!failed && socket != null) {
            try {
                // with this round's round-trip and work-time statistics (a dead robot's output is not collected)
                if (keepHistory) {
                    record();  // the state this robot ends the round in
                }
                if (acting != null) {
                    while (in.ready()) {
                        in.readLine();  // updates not yet read: closing with them unread resets the connection
                    }
                }
                // sent before any blocking read: after the battle's last round the engine stops a robot that
                // takes too long in its handlers, and the end line must be out by then
                send("E " + getRoundNum() + " " + getTime() + " " + how + " " + getEnergy() + " " + rttN + " "
                        + rttSum / 1000 + " " + rttSlow + " " + turnsPlayed + " " + workNanos / 1000 + "\t" + history);
                // a FIN right behind the end line: if the engine stops this thread before the answer below is
                // read, closing with it unread sends a reset, which can make the server lose a line not yet read
                socket.shutdownOutput();
                if (pending) {
                    in.readLine();  // the answer to a request sent ahead (lead): closing with it unread resets
                    pending = false;
                }
            } catch (IOException e) {
                // the round is over anyway
            }
        }
        close();
    }

    @Override
    public void onDeath(DeathEvent e) {
        finish("death");
    }

    @Override
    public void onWin(WinEvent e) {
        // the round goes on for a while after a win; the connection stays open until the round ends
    }

    @Override
    public void onRoundEnded(RoundEndedEvent e) {
        finish("round_end");
    }

    /** JSON string literal (names contain only printable characters). */
    static String str(String s) {
        return "\"" + s.replace("\\", "\\\\").replace("\"", "\\\"") + "\"";
    }
}
