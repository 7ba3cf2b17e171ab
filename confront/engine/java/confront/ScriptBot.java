package confront;

import java.io.BufferedReader;
import java.io.File;
import java.io.FileReader;
import java.io.IOException;
import java.util.ArrayList;
import java.util.HashMap;
import java.util.List;
import java.util.Map;

import robocode.AdvancedRobot;
import robocode.BulletHitBulletEvent;
import robocode.BulletHitEvent;
import robocode.BulletMissedEvent;
import robocode.DeathEvent;
import robocode.HitByBulletEvent;
import robocode.HitRobotEvent;
import robocode.HitWallEvent;
import robocode.RobotDeathEvent;
import robocode.ScannedRobotEvent;
import robocode.SkippedTurnEvent;
import robocode.WinEvent;

/**
 * An AdvancedRobot that plays a command script from its data directory and prints the events it sees.
 *
 * Script file: script.txt, or script_K.txt for the K-th copy ("Name (K)"). Lines: "flag NAME VALUE"
 * (adjust_gun_for_robot_turn, adjust_radar_for_robot_turn, adjust_radar_for_gun_turn: 0/1; max_velocity,
 * max_turn_rate_deg: number) or "TURN COMMAND VALUE" with COMMAND one of ahead (px), turn, gun, radar
 * (radians, + clockwise), fire (power), max_velocity; the command is set in the turn before TURN so that it
 * takes effect in engine turn TURN. Every event is printed as a line "EV {json}".
 */
public class ScriptBot extends AdvancedRobot {
    private final Map<Long, List<String[]>> script = new HashMap<>();

    @Override
    public void run() {
        try {
            load();
        } catch (IOException e) {
            out.println("EV {\"type\":\"script_error\",\"time\":0,\"message\":\"" + e.getMessage() + "\"}");
        }
        while (true) {
            List<String[]> now = script.get(getTime() + 1);
            if (now != null) {
                for (String[] c : now) {
                    apply(c[1], Double.parseDouble(c[2]));
                }
            }
            execute();
        }
    }

    private void load() throws IOException {
        String name = getName();
        String file = "script.txt";
        int open = name.lastIndexOf(" (");
        if (open >= 0 && name.endsWith(")")) {
            file = "script_" + name.substring(open + 2, name.length() - 1) + ".txt";
        }
        File f = getDataFile(file);
        if (!f.exists()) {
            f = getDataFile("script.txt");
        }
        try (BufferedReader r = new BufferedReader(new FileReader(f))) {
            String line;
            while ((line = r.readLine()) != null) {
                line = line.trim();
                if (line.isEmpty() || line.startsWith("#")) {
                    continue;
                }
                String[] p = line.split("\\s+");
                if (p[0].equals("flag")) {
                    flag(p[1], Double.parseDouble(p[2]));
                } else {
                    script.computeIfAbsent(Long.parseLong(p[0]), k -> new ArrayList<>()).add(p);
                }
            }
        }
    }

    private void flag(String name, double v) {
        switch (name) {
            case "adjust_gun_for_robot_turn": setAdjustGunForRobotTurn(v != 0); break;
            case "adjust_radar_for_robot_turn": setAdjustRadarForRobotTurn(v != 0); break;
            case "adjust_radar_for_gun_turn": setAdjustRadarForGunTurn(v != 0); break;
            case "max_velocity": setMaxVelocity(v); break;
            case "max_turn_rate_deg": setMaxTurnRate(v); break;
            default: throw new IllegalArgumentException("unknown flag " + name);
        }
    }

    private void apply(String cmd, double v) {
        switch (cmd) {
            case "ahead": setAhead(v); break;
            case "turn": setTurnRightRadians(v); break;
            case "gun": setTurnGunRightRadians(v); break;
            case "radar": setTurnRadarRightRadians(v); break;
            case "fire": setFire(v); break;
            case "max_velocity": setMaxVelocity(v); break;
            default: throw new IllegalArgumentException("unknown command " + cmd);
        }
    }

    private void ev(String type, long time, String rest) {
        out.println("EV {\"type\":\"" + type + "\",\"time\":" + time + (rest.isEmpty() ? "" : "," + rest) + "}");
    }

    private static String q(String s) {
        return "\"" + s.replace("\\", "\\\\").replace("\"", "\\\"") + "\"";
    }

    @Override
    public void onHitWall(HitWallEvent e) {
        ev("hit_wall", e.getTime(), "\"bearing\":" + e.getBearingRadians());
    }

    @Override
    public void onHitRobot(HitRobotEvent e) {
        ev("hit_robot", e.getTime(), "\"name\":" + q(e.getName()) + ",\"bearing\":" + e.getBearingRadians()
                + ",\"energy\":" + e.getEnergy() + ",\"my_fault\":" + e.isMyFault());
    }

    @Override
    public void onHitByBullet(HitByBulletEvent e) {
        ev("hit_by_bullet", e.getTime(), "\"name\":" + q(e.getName()) + ",\"power\":" + e.getPower()
                + ",\"bearing\":" + e.getBearingRadians());
    }

    @Override
    public void onBulletHit(BulletHitEvent e) {
        ev("bullet_hit", e.getTime(), "\"name\":" + q(e.getName()) + ",\"energy\":" + e.getEnergy()
                + ",\"power\":" + e.getBullet().getPower());
    }

    @Override
    public void onBulletHitBullet(BulletHitBulletEvent e) {
        ev("bullet_hit_bullet", e.getTime(), "\"power\":" + e.getBullet().getPower()
                + ",\"other_power\":" + e.getHitBullet().getPower());
    }

    @Override
    public void onBulletMissed(BulletMissedEvent e) {
        ev("bullet_missed", e.getTime(), "\"power\":" + e.getBullet().getPower());
    }

    @Override
    public void onScannedRobot(ScannedRobotEvent e) {
        ev("scanned_robot", e.getTime(), "\"name\":" + q(e.getName()) + ",\"bearing\":" + e.getBearingRadians()
                + ",\"distance\":" + e.getDistance() + ",\"heading\":" + e.getHeadingRadians()
                + ",\"velocity\":" + e.getVelocity() + ",\"energy\":" + e.getEnergy());
    }

    @Override
    public void onRobotDeath(RobotDeathEvent e) {
        ev("robot_death", e.getTime(), "\"name\":" + q(e.getName()));
    }

    @Override
    public void onDeath(DeathEvent e) {
        ev("death", e.getTime(), "");
    }

    @Override
    public void onWin(WinEvent e) {
        ev("win", e.getTime(), "");
    }

    @Override
    public void onSkippedTurn(SkippedTurnEvent e) {
        ev("skipped_turn", e.getTime(), "\"skipped\":" + e.getSkippedTurn());
    }
}
