package confront;

import java.io.BufferedReader;
import java.io.IOException;
import java.io.InputStreamReader;
import java.io.OutputStream;
import java.net.InetAddress;
import java.net.InetSocketAddress;
import java.net.Socket;
import java.nio.charset.StandardCharsets;
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
 * A tank that hands every turn's decision to a Python policy over a loopback TCP socket.
 *
 * Settings come from JVM system properties (the engine runs with -DNOSECURITY=true so that robots may use
 * sockets): confront.bridge.port, confront.bridge.token, confront.bridge.timeoutMs, confront.bridge.every
 * (ask Python in every k-th turn only; the commands keep running in between). Protocol version 1,
 * one line per message: the robot sends a JSON "hello" once per round, then an "O ..." observation line
 * every turn and "E ..." at death or round end (format in confront/engine/bridge.py); Python answers
 * "OK 1" to hello and "A TURN AHEAD TURN GUN RADAR FIRE" to each observation
 * (radians, + clockwise; "NaN" keeps the current remaining value; fire 0 = no shot). Any missing, late
 * or malformed answer switches the robot to a built-in behaviour for the rest of the round and prints
 * "CONFRONT bridge-failed REASON" for the runner to report.
 */
public class BridgeBot extends TeamRobot {
    static final int VERSION = 1;
    private Socket socket;
    private BufferedReader in;
    private OutputStream out2;
    private boolean failed;
    private boolean finished;
    private long rttN;
    private long rttSum;
    private long rttSlow;
    private final Map<String, String> scans = new LinkedHashMap<>();
    private final StringBuilder events = new StringBuilder();
    private double enemyBearing = Double.NaN;
    private long lastScan = -100;

    @Override
    public void run() {
        setAdjustGunForRobotTurn(true);
        setAdjustRadarForRobotTurn(true);
        setAdjustRadarForGunTurn(true);
        // act once before connecting, after giving the engine time to wait for this first action
        RoundStart.awaitEngine();
        execute();
        connect();
        int every = Integer.parseInt(System.getProperty("confront.bridge.every", "1"));
        while (true) {
            if (!failed && !finished && (getTime() + 1) % every == 0) {
                try {
                    decide();
                } catch (IOException | RuntimeException e) {
                    fail(e.getClass().getSimpleName() + ": " + e.getMessage());
                }
            }
            if (failed) {
                fallback();
            }
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
            send("{\"v\":" + VERSION + ",\"type\":\"hello\",\"token\":" + str(System.getProperty("confront.bridge.token", ""))
                    + ",\"name\":" + str(getName()) + ",\"team\":" + str(teamName())
                    + ",\"round\":" + getRoundNum() + ",\"rounds\":" + getNumRounds()
                    + ",\"width\":" + getBattleFieldWidth() + ",\"height\":" + getBattleFieldHeight() + "}");
            String reply = in.readLine();
            if (!("OK " + VERSION).equals(reply)) {
                fail("bad hello reply " + reply);
            }
        } catch (IOException | RuntimeException e) {
            fail("connect: " + e.getClass().getSimpleName() + ": " + e.getMessage());
        }
    }

    private String teamName() {
        String[] mates = getTeammates();
        return mates == null ? "" : String.join(";", mates);
    }

    private void decide() throws IOException {
        long turn = getTime() + 1;  // the commands set now take effect in this engine turn
        StringBuilder b = new StringBuilder(256);
        b.append("O ").append(getRoundNum()).append(' ').append(turn)
                .append(' ').append(getX()).append(' ').append(getY())
                .append(' ').append(getHeadingRadians()).append(' ').append(getGunHeadingRadians())
                .append(' ').append(getRadarHeadingRadians()).append(' ').append(getVelocity())
                .append(' ').append(getEnergy()).append(' ').append(getGunHeat())
                .append(' ').append(getOthers()).append(' ').append(getDistanceRemaining())
                .append('\t').append(String.join("|", scans.values()))
                .append("\t[").append(events).append(']');
        events.setLength(0);
        long t0 = System.nanoTime();
        send(b.toString());
        String line = in.readLine();
        long dt = System.nanoTime() - t0;
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

    private void send(String json) throws IOException {
        out2.write((json + "\n").getBytes(StandardCharsets.UTF_8));
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
        if (!mate) {
            enemyBearing = e.getBearingRadians();
            lastScan = e.getTime();
        }
        scans.put(e.getName(), e.getName() + ";" + e.getTime() + ";" + (mate ? 1 : 0)
                + ";" + e.getBearingRadians() + ";" + e.getDistance() + ";" + e.getHeadingRadians()
                + ";" + e.getVelocity() + ";" + e.getEnergy()
                + ";" + (getX() + e.getDistance() * Math.sin(abs))
                + ";" + (getY() + e.getDistance() * Math.cos(abs)));
    }

    @Override
    public void onRobotDeath(RobotDeathEvent e) {
        scans.remove(e.getName());
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
        // round-trip statistics of this round, for the runner's report
        out.println("CONFRONT bridge-stats round=" + getRoundNum() + " decisions=" + rttN + " rtt_total_us="
                + rttSum / 1000 + " rtt_over_1ms=" + rttSlow);
        finished = true;
        if (!failed && socket != null) {
            try {
                send("E " + getRoundNum() + " " + getTime() + " " + how + " " + getEnergy());
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
