package confront;

import java.io.BufferedWriter;
import java.io.File;
import java.io.FileInputStream;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.OutputStreamWriter;
import java.io.PrintStream;
import java.io.Writer;
import java.nio.charset.StandardCharsets;
import java.util.ArrayList;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;
import java.util.Properties;

import net.sf.robocode.battle.BattleResultsTableModel;
import robocode.BattleResults;
import robocode.control.BattleSpecification;
import robocode.control.BattlefieldSpecification;
import robocode.control.RobocodeEngine;
import robocode.control.RobotSpecification;
import robocode.control.events.BattleAdaptor;
import robocode.control.events.BattleCompletedEvent;
import robocode.control.events.BattleErrorEvent;
import robocode.control.events.BattleMessageEvent;
import robocode.control.events.RoundEndedEvent;
import robocode.control.events.RoundStartedEvent;
import robocode.control.events.TurnEndedEvent;
import robocode.control.snapshot.IBulletSnapshot;
import robocode.control.snapshot.IRobotSnapshot;
import robocode.control.snapshot.IScoreSnapshot;
import robocode.control.snapshot.ITurnSnapshot;

/**
 * Runs one battle file headless on Robocode's control API.
 *
 * Writes the engine's own results table (same writer as the command line's -results), a JSON summary
 * (turn counts, skipped turns, exact score parts per robot and per contestant, timings, the CPUs the JVM may
 * use) and, when asked,
 * a JSONL trace of every turn. Arguments: WORKDIR BATTLE_FILE RESULTS_FILE SUMMARY_FILE [TRACE_FILE].
 *
 * <p>With the JVM property confront.scores=PATH it also writes each robot's current-round score per turn
 * (PPO training in the engine, confront.train.ppo_engine): a line "round turn alive s_0 ... s_n-1"
 * (robots in snapshot order, alive a string of 0/1, scores by Double.toString) at each round's first turn and
 * whenever a score or a robot's life changed since the line before.
 */
public final class ConfrontRunner extends BattleAdaptor {
    private final Writer trace;
    private final long startNanos = System.nanoTime();
    private long lastTurnNanos = System.nanoTime();
    private long setupNanos;
    private boolean firstTurnOfRound;
    private long turns;
    private long robotTurns;
    private final List<Integer> roundTurns = new ArrayList<>();
    private final StringBuilder roundScores = new StringBuilder();
    private final Map<String, Integer> skipped = new LinkedHashMap<>();
    private final List<String> errors = new ArrayList<>();
    private final List<String> messages = new ArrayList<>();
    private final List<String> reports = new ArrayList<>();
    private ITurnSnapshot last;
    private BattleCompletedEvent completed;
    private RobocodeEngine engine;
    private int maxTurns;
    private int abortedAt = -1;
    private Writer scores;  // confront.scores: per-turn current scores, written on change
    private double[] lastScores = new double[0];
    private String lastAlive = "";
    private int scoresRound = -1;

    private ConfrontRunner(Writer trace) {
        this.trace = trace;
    }

    public static void main(String[] args) throws Exception {
        if (args.length < 4) {
            System.err.println("usage: ConfrontRunner WORKDIR BATTLE RESULTS SUMMARY [TRACE]");
            System.exit(2);
        }
        Properties battle = new Properties();
        try (FileInputStream in = new FileInputStream(args[1])) {
            battle.load(in);
        }
        Writer trace = null;
        if (args.length > 4) {
            trace = new BufferedWriter(new OutputStreamWriter(new FileOutputStream(args[4]), StandardCharsets.UTF_8));
        }
        RobocodeEngine.setLogMessagesEnabled(false);
        RobocodeEngine engine = new RobocodeEngine(new File(args[0]));
        ConfrontRunner runner = new ConfrontRunner(trace);
        runner.engine = engine;
        runner.maxTurns = Integer.parseInt(battle.getProperty("confront.maxTurns", "0"));
        String scorePath = System.getProperty("confront.scores");
        if (scorePath != null && !scorePath.isEmpty()) {
            runner.scores = new BufferedWriter(new OutputStreamWriter(new FileOutputStream(scorePath),
                    StandardCharsets.UTF_8));
        }
        engine.addBattleListener(runner);
        int exit = 0;
        try {
            String selected = battle.getProperty("robocode.battle.selectedRobots", "");
            RobotSpecification[] robots = engine.getLocalRepository(selected);
            int expected = Integer.parseInt(battle.getProperty("confront.expectedRobots", "-1"));
            if (robots == null || robots.length == 0 || (expected >= 0 && robots.length != expected)) {
                runner.errors.add("robots not found: wanted " + selected + ", got "
                        + (robots == null ? 0 : robots.length) + " robot(s)");
                exit = 3;
            } else {
                BattlefieldSpecification field = new BattlefieldSpecification(
                        Integer.parseInt(battle.getProperty("robocode.battleField.width", "800")),
                        Integer.parseInt(battle.getProperty("robocode.battleField.height", "600")));
                BattleSpecification spec = new BattleSpecification(
                        Integer.parseInt(battle.getProperty("robocode.battle.numRounds", "10")),
                        Long.parseLong(battle.getProperty("robocode.battle.rules.inactivityTime", "450")),
                        Double.parseDouble(battle.getProperty("robocode.battle.gunCoolingRate", "0.1")),
                        false, field, robots);
                if (trace != null) {
                    runner.writeHeader(spec, robots, battle);
                }
                String positions = battle.getProperty("robocode.battle.initialPositions");
                if (Boolean.getBoolean("confront.visible")) {
                    engine.setVisible(true);  // Robocode's own battle window (needs a display)
                }
                engine.runBattle(spec, positions, true);
                if (runner.completed == null && runner.abortedAt < 0) {
                    runner.errors.add("battle did not complete");
                    exit = 4;
                }
            }
            runner.writeResults(args[2]);
            runner.writeSummary(args[3], robots == null ? 0 : robots.length);
        } finally {
            if (trace != null) {
                trace.close();
            }
            if (runner.scores != null) {
                runner.scores.close();
            }
            engine.close();
        }
        System.exit(exit);
    }

    private void writeHeader(BattleSpecification spec, RobotSpecification[] robots, Properties battle)
            throws IOException {
        StringBuilder b = new StringBuilder();
        b.append("{\"type\":\"battle\",\"width\":").append(spec.getBattlefield().getWidth())
                .append(",\"height\":").append(spec.getBattlefield().getHeight())
                .append(",\"rounds\":").append(spec.getNumRounds())
                .append(",\"gun_cooling_rate\":").append(spec.getGunCoolingRate())
                .append(",\"inactivity_time\":").append(spec.getInactivityTime())
                .append(",\"initial_positions\":")
                .append(str(battle.getProperty("robocode.battle.initialPositions", "")))
                .append(",\"robots\":[");
        for (int i = 0; i < robots.length; i++) {
            if (i > 0) {
                b.append(',');
            }
            b.append("{\"index\":").append(i).append(",\"class\":").append(str(robots[i].getClassName()))
                    .append(",\"team\":").append(str(robots[i].getTeamId())).append('}');
        }
        b.append("]}\n");
        trace.write(b.toString());
    }

    @Override
    public void onRoundStarted(RoundStartedEvent event) {
        firstTurnOfRound = true;
        if (trace != null) {
            writeTurn(event.getStartSnapshot(), "round_start");
        }
    }

    @Override
    public void onTurnEnded(TurnEndedEvent event) {
        ITurnSnapshot snap = event.getTurnSnapshot();
        long now = System.nanoTime();
        if (firstTurnOfRound) {
            // time from the previous round's last turn (or engine start) to this round's first turn
            setupNanos += now - lastTurnNanos;
            firstTurnOfRound = false;
        }
        lastTurnNanos = now;
        turns++;
        for (IRobotSnapshot r : snap.getRobots()) {
            if (r.getState() != robocode.control.snapshot.RobotState.DEAD) {
                robotTurns++;
            }
            String out = r.getOutputStreamSnapshot();
            if (out != null && out.contains("CONFRONT ") && reports.size() < 1000) {
                for (String line : out.split("\n")) {
                    if (line.startsWith("CONFRONT ")) {
                        reports.add(r.getName() + ": " + line.substring(9));
                    }
                }
            }
            if (out != null && out.contains(" skipped turn ")) {
                int n = 0;
                for (String line : out.split("\n")) {
                    if (line.startsWith("SYSTEM: ") && line.contains(" skipped turn ")) {
                        n++;
                        if (reports.size() < 1000) {
                            reports.add(r.getName() + ": skipped round=" + snap.getRound() + " "
                                    + line.substring(line.indexOf(" skipped turn ") + 1));
                        }
                    }
                }
                skipped.merge(r.getName(), n, Integer::sum);
            }
        }
        last = snap;
        if (abortedAt >= 0) {
            return;
        }
        if (scores != null) {
            writeCurrentScores(snap);
        }
        if (trace != null) {
            writeTurn(snap, "turn");
        }
        if (maxTurns > 0 && snap.getTurn() >= maxTurns) {
            abortedAt = snap.getTurn();
            if (trace != null) {
                writeScores("stopped", snap.getRound(), snap.getTurn(), snap);
            }
            // aborting waits for the battle thread, which is the caller here: do it from another thread
            Thread stopper = new Thread(engine::abortCurrentBattle, "confront-stop");
            stopper.setDaemon(true);
            stopper.start();
        }
    }

    /** The confront.scores line of this turn, when a score or a robot's life changed (or a round began). */
    private void writeCurrentScores(ITurnSnapshot snap) {
        IRobotSnapshot[] rs = snap.getRobots();
        StringBuilder alive = new StringBuilder(rs.length);
        boolean changed = snap.getRound() != scoresRound || lastScores.length != rs.length;
        if (changed) {
            lastScores = new double[rs.length];
        }
        for (int i = 0; i < rs.length; i++) {
            alive.append(rs[i].getState() == robocode.control.snapshot.RobotState.DEAD ? '0' : '1');
            double s = rs[i].getScoreSnapshot().getCurrentScore();
            if (s != lastScores[i]) {
                changed = true;
                lastScores[i] = s;
            }
        }
        if (!changed && alive.toString().equals(lastAlive)) {
            return;
        }
        scoresRound = snap.getRound();
        lastAlive = alive.toString();
        StringBuilder b = new StringBuilder(32 + 24 * rs.length);
        b.append(snap.getRound()).append(' ').append(snap.getTurn()).append(' ').append(lastAlive);
        for (double s : lastScores) {
            b.append(' ').append(Double.toString(s));
        }
        b.append('\n');
        try {
            scores.write(b.toString());
        } catch (IOException e) {
            errors.add("score log write failed: " + e.getMessage());
        }
    }

    @Override
    public void onRoundEnded(RoundEndedEvent event) {
        roundTurns.add(event.getTurns());
        if (last != null && abortedAt < 0) {
            roundScore(event.getRound(), event.getTurns(), last);
        }
        if (trace != null && last != null && abortedAt < 0) {
            writeScores("round_end", event.getRound(), event.getTurns(), last);
        }
    }

    /**
     * Per robot its battle totals so far (exact doubles) and whether it is alive, at the round's end. Per-round
     * parts are differences of these: a robot's "current" round score can grow after its death (its bullets
     * still in flight) while its totals, which the results file adds up, were closed at its death.
     */
    private void roundScore(int round, int turns, ITurnSnapshot snap) {
        if (roundScores.length() > 0) {
            roundScores.append(',');
        }
        roundScores.append("{\"round\":").append(round).append(",\"turns\":").append(turns)
                .append(",\"robots\":[");
        IRobotSnapshot[] rs = snap.getRobots();
        for (int i = 0; i < rs.length; i++) {
            if (i > 0) {
                roundScores.append(',');
            }
            roundScores.append("{\"contestant\":").append(rs[i].getContestantIndex())
                    .append(",\"alive\":").append(rs[i].getState() != robocode.control.snapshot.RobotState.DEAD)
                    .append(",\"score\":");
            score(roundScores, rs[i].getScoreSnapshot());
            roundScores.append('}');
        }
        roundScores.append("]}");
    }

    private void writeScores(String type, int round, int turns, ITurnSnapshot snap) {
        StringBuilder b = new StringBuilder();
        b.append("{\"type\":\"").append(type).append("\",\"round\":").append(round)
                .append(",\"turns\":").append(turns).append(",\"robots\":[");
        IRobotSnapshot[] rs = snap.getRobots();
        for (int i = 0; i < rs.length; i++) {
            if (i > 0) {
                b.append(',');
            }
            b.append("{\"index\":").append(i).append(",\"name\":").append(str(rs[i].getName()))
                    .append(",\"score\":");
            score(b, rs[i].getScoreSnapshot());
            b.append(",\"current\":");
            current(b, rs[i].getScoreSnapshot());
            b.append('}');
        }
        b.append("]}\n");
        write(b.toString());
    }

    @Override
    public void onBattleCompleted(BattleCompletedEvent event) {
        completed = event;
    }

    @Override
    public void onBattleError(BattleErrorEvent event) {
        errors.add(event.getError());
    }

    @Override
    public void onBattleMessage(BattleMessageEvent event) {
        if (messages.size() < 200) {
            messages.add(event.getMessage());
        }
    }

    private void writeTurn(ITurnSnapshot snap, String type) {
        StringBuilder b = new StringBuilder(512);
        b.append("{\"type\":\"").append(type).append("\",\"round\":").append(snap.getRound())
                .append(",\"turn\":").append(snap.getTurn()).append(",\"robots\":[");
        IRobotSnapshot[] rs = snap.getRobots();
        StringBuilder events = new StringBuilder();
        for (int i = 0; i < rs.length; i++) {
            IRobotSnapshot r = rs[i];
            if (i > 0) {
                b.append(',');
            }
            b.append("{\"index\":").append(i)
                    .append(",\"x\":").append(r.getX()).append(",\"y\":").append(r.getY())
                    .append(",\"body_heading\":").append(r.getBodyHeading())
                    .append(",\"gun_heading\":").append(r.getGunHeading())
                    .append(",\"radar_heading\":").append(r.getRadarHeading())
                    .append(",\"velocity\":").append(r.getVelocity())
                    .append(",\"energy\":").append(r.getEnergy())
                    .append(",\"gun_heat\":").append(r.getGunHeat())
                    .append(",\"state\":\"").append(r.getState().name()).append("\"}");
            String out = r.getOutputStreamSnapshot();
            if (out != null) {
                for (String line : out.split("\n")) {
                    if (line.startsWith("EV {")) {
                        if (events.length() > 0) {
                            events.append(',');
                        }
                        events.append("{\"robot\":").append(i).append(',').append(line.substring(4));
                    }
                }
            }
        }
        b.append("],\"bullets\":[");
        boolean first = true;
        for (IBulletSnapshot s : snap.getBullets()) {
            if (s.isExplosion() && s.getOwnerIndex() < 0) {
                continue;
            }
            if (!first) {
                b.append(',');
            }
            first = false;
            b.append("{\"id\":").append(s.getBulletId()).append(",\"owner\":").append(s.getOwnerIndex())
                    .append(",\"victim\":").append(s.getVictimIndex())
                    .append(",\"state\":\"").append(s.getState().name()).append('"')
                    .append(",\"x\":").append(s.getX()).append(",\"y\":").append(s.getY())
                    .append(",\"heading\":").append(s.getHeading()).append(",\"power\":").append(s.getPower())
                    .append(",\"explosion\":").append(s.isExplosion()).append(",\"frame\":").append(s.getFrame())
                    .append('}');
        }
        b.append("],\"events\":[").append(events).append("]}\n");
        write(b.toString());
    }

    private void write(String s) {
        try {
            trace.write(s);
        } catch (IOException e) {
            errors.add("trace write failed: " + e.getMessage());
        }
    }

    private void writeResults(String path) throws IOException {
        try (PrintStream out = new PrintStream(new FileOutputStream(path), false, "UTF-8")) {
            if (completed != null) {
                BattleResultsTableModel model = new BattleResultsTableModel(
                        completed.getSortedResults(), completed.getBattleRules().getNumRounds());
                model.print(out);
            }
        }
    }

    private void writeSummary(String path, int nRobots) throws IOException {
        StringBuilder b = new StringBuilder();
        double elapsed = (System.nanoTime() - startNanos) / 1e9;
        b.append("{\"completed\":").append(completed != null || abortedAt >= 0)
                .append(",\"stopped_at_turn\":").append(abortedAt)
                .append(",\"robots_requested\":").append(nRobots)
                .append(",\"turns\":").append(turns).append(",\"robot_turns\":").append(robotTurns)
                .append(",\"elapsed_s\":").append(elapsed)
                .append(",\"setup_s\":").append(setupNanos / 1e9)
                .append(",\"cpus\":").append(Runtime.getRuntime().availableProcessors())
                .append(",\"round_turns\":").append(roundTurns.toString())
                .append(",\"round_scores\":[").append(roundScores).append(']')
                .append(",\"skipped_turns\":{");
        boolean first = true;
        for (Map.Entry<String, Integer> e : skipped.entrySet()) {
            if (!first) {
                b.append(',');
            }
            first = false;
            b.append(str(e.getKey())).append(':').append(e.getValue());
        }
        b.append("},\"robots\":[");
        if (last != null) {
            IRobotSnapshot[] rs = last.getRobots();
            for (int i = 0; i < rs.length; i++) {
                if (i > 0) {
                    b.append(',');
                }
                b.append("{\"name\":").append(str(rs[i].getName()))
                        .append(",\"team\":").append(str(rs[i].getTeamName()))
                        .append(",\"contestant\":").append(rs[i].getContestantIndex())
                        .append(",\"score\":");
                score(b, rs[i].getScoreSnapshot());
                b.append('}');
            }
        }
        b.append("],\"contestants\":[");
        if (last != null) {
            IScoreSnapshot[] ts = last.getIndexedTeamScores();
            for (int i = 0; i < ts.length; i++) {
                if (i > 0) {
                    b.append(',');
                }
                b.append("{\"name\":").append(str(ts[i].getName())).append(",\"score\":");
                score(b, ts[i]);
                b.append('}');
            }
        }
        b.append("],\"results\":[");
        if (completed != null) {
            BattleResults[] res = completed.getSortedResults();
            for (int i = 0; i < res.length; i++) {
                if (i > 0) {
                    b.append(',');
                }
                b.append("{\"name\":").append(str(res[i].getTeamLeaderName()))
                        .append(",\"rank\":").append(res[i].getRank()).append('}');
            }
        }
        b.append("],\"errors\":[");
        appendStrings(b, errors);
        b.append("],\"robot_reports\":[");
        appendStrings(b, reports);
        b.append("],\"messages\":[");
        appendStrings(b, messages);
        b.append("]}\n");
        try (Writer w = new OutputStreamWriter(new FileOutputStream(path), StandardCharsets.UTF_8)) {
            w.write(b.toString());
        }
    }

    /** The score fields of a results row, in the order score() and current() give their values. */
    private static final String[] SCORE_KEYS = {"total", "survival", "surv_bonus", "bullet_dmg", "bullet_bonus",
        "ram_dmg", "ram_bonus"};

    /** The battle's totals so far: the score fields, then the ranks (firsts, seconds, thirds). */
    private static void score(StringBuilder b, IScoreSnapshot s) {
        fields(b, new double[] {s.getTotalScore(), s.getTotalSurvivalScore(), s.getTotalLastSurvivorBonus(),
            s.getTotalBulletDamageScore(), s.getTotalBulletKillBonus(), s.getTotalRammingDamageScore(),
            s.getTotalRammingKillBonus()});
        b.append(",\"firsts\":").append(s.getTotalFirsts()).append(",\"seconds\":").append(s.getTotalSeconds())
                .append(",\"thirds\":").append(s.getTotalThirds()).append('}');
    }

    /** This round's score fields. */
    private static void current(StringBuilder b, IScoreSnapshot s) {
        fields(b, new double[] {s.getCurrentScore(), s.getCurrentSurvivalScore(), s.getCurrentSurvivalBonus(),
            s.getCurrentBulletDamageScore(), s.getCurrentBulletKillBonus(), s.getCurrentRammingDamageScore(),
            s.getCurrentRammingKillBonus()});
        b.append('}');
    }

    /** {"total":v0,"survival":v1,... of SCORE_KEYS (the object left open). */
    private static void fields(StringBuilder b, double[] values) {
        for (int i = 0; i < SCORE_KEYS.length; i++) {
            b.append(i == 0 ? "{\"" : ",\"").append(SCORE_KEYS[i]).append("\":").append(values[i]);
        }
    }

    private static void appendStrings(StringBuilder b, List<String> items) {
        for (int i = 0; i < items.size(); i++) {
            if (i > 0) {
                b.append(',');
            }
            b.append(str(items.get(i)));
        }
    }

    /** JSON string literal. */
    static String str(String s) {
        if (s == null) {
            return "null";
        }
        StringBuilder b = new StringBuilder(s.length() + 2).append('"');
        for (char c : s.toCharArray()) {
            switch (c) {
                case '"': b.append("\\\""); break;
                case '\\': b.append("\\\\"); break;
                case '\n': b.append("\\n"); break;
                case '\r': b.append("\\r"); break;
                case '\t': b.append("\\t"); break;
                default:
                    if (c < 0x20) {
                        b.append(String.format("\\u%04x", (int) c));
                    } else {
                        b.append(c);
                    }
            }
        }
        return b.append('"').toString();
    }
}
