package confront.tech;

import java.util.Random;

import robocode.util.Utils;

/**
 * The decisions of the classic Robocode techniques (one gun and one movement), apart from any robot: TechBot
 * feeds it its events and state each turn and sets the commands it proposes; TankBot runs one for the learning
 * tank's skills (its GuessFactor aim, its surfing moves) and for what it knows about the battle (knowledge()).
 *
 * Guns: head-on, linear, circular, GuessFactor (visit counts per segment: distance, lateral velocity,
 * acceleration, distance to the wall ahead), virtual guns (the gun with the best rolling hit rate), an
 * anti-surfer GuessFactor gun (visit counts per distance segment that fade at each visit, AS_DECAY; it aims
 * while its rolling hit rate beats the GuessFactor aim's by AS_MARGIN, else the GuessFactor aim does).
 * Movements: random orbit with wall smoothing, stop-and-go, ramming, wave surfing (waves from the enemy's
 * energy drops, precise prediction of our own path, danger from where its bullets hit us), minimum risk
 * (melee: used while more than one other robot is alive).
 *
 * Written so that the simulator's twin (confront/arena/tech.py) can follow it exactly: one decision per turn
 * (the event handlers only record), radians, Math.atan2 / Math.hypot and StrictMath.sin / cos (fdlibm,
 * reproduced by the simulator: Math.sin is a HotSpot intrinsic), java.util.Random seeded from the first
 * round's start position. What a robot learns (visit counts, hit statistics, gun hit rates, the generator) is
 * kept in static fields: the engine loads a robot's classes once per battle (each robot its own class loader),
 * so it lives for the battle's rounds; a brain object lives for one round.
 */
public final class TechBrain {
    public static final int G_HEAD = 0, G_LINEAR = 1, G_CIRCULAR = 2, G_GF = 3, G_VIRTUAL = 4, G_AS = 5;
    public static final int M_ORBIT = 0, M_STOPGO = 1, M_RAM = 2, M_SURF = 3, M_RISK = 4;
    static final int BINS = 31, MID = 15;
    static final int SEGMENTS = 5 * 3 * 3 * 3;
    static final int MAXE = 10, MAXW = 16, MAXG = 64, NGUNS = 4;
    static final double HALF_PI = Math.PI / 2, TWO_PI = 2 * Math.PI, DEG = Math.PI / 180;
    public static final double SPIN = 10000;
    static final double STICK = 140, MARGIN = 25;
    /** Length of knowledge(). */
    public static final int KNOWLEDGE = 8;
    static final double MAX_IMPACT = 50;  // turns: a wave further away (or none) reads as 1
    static final double AS_DECAY = 0.7, AS_MARGIN = 0.03;

    // battle memory (one class load per battle)
    static Random rng;
    static double[] gf = new double[SEGMENTS * BINS];
    static double[] surf = new double[BINS];
    static double[] vgRate = new double[NGUNS];
    static double[] asVisits = new double[5 * BINS];  // per distance segment, fading
    static double asRate;  // the anti-surfer aim's rolling hit rate

    private final int gunKind, moveKind;
    private final double fieldWidth, fieldHeight;
    /** The last decision's commands: ahead, turn right, gun turn right, radar turn right (rad; NaN = not set),
     *  fire power (0 = none). */
    public final double[] cmd = new double[5];
    /** The last decision's GuessFactor aim: its enemy slot (-1: none this turn), the GuessFactor (+ = the
     *  enemy's lateral direction; x the escape angle gives the angle from its bearing), the bin's share of its
     *  segment's visits. */
    int aimSlot = -1;
    double aimFactor, aimPeak;
    // the robot's state at this decision
    private double heading, velocity, energy, gunHeading, gunHeat, gunTurnRemaining;

    // enemies (slots in the order first seen this round)
    final String[] eName = new String[MAXE];
    int nE;
    final double[] ex = new double[MAXE], ey = new double[MAXE], eh = new double[MAXE], ev = new double[MAXE],
            ee = new double[MAXE], ed = new double[MAXE], eb = new double[MAXE], pex = new double[MAXE],
            pey = new double[MAXE], peh = new double[MAXE], pev = new double[MAXE], pee = new double[MAXE];
    final long[] eScan = new long[MAXE], ePrevScan = new long[MAXE];
    final boolean[] eAlive = new boolean[MAXE], eMate = new boolean[MAXE];
    // this turn's bullet events: powers of bullets that hit us (with their headings) and of ours that hit
    final double[] hitPower = new double[8], hitHeading = new double[8];
    int nHit;
    double myHitDamage;
    // enemy waves: source, fire time, speed, direct angle, lateral direction
    final double[] wx = new double[MAXW], wy = new double[MAXW], wt = new double[MAXW], ws = new double[MAXW],
            wa = new double[MAXW], wd = new double[MAXW];
    final boolean[] wOn = new boolean[MAXW];
    // gun waves: source, fire time, speed, direct angle, lateral direction, escape angle, segment, target,
    // and every virtual gun's aim
    final double[] gx = new double[MAXG], gy = new double[MAXG], gt = new double[MAXG], gs = new double[MAXG],
            ga = new double[MAXG], gd = new double[MAXG], gm = new double[MAXG];
    final int[] gSeg = new int[MAXG], gTarget = new int[MAXG];
    final double[] gAim = new double[MAXG * NGUNS], gAsAim = new double[MAXG];
    final boolean[] gOn = new boolean[MAXG];
    int gNext;
    double moveDir = 1, gunDir = 1, destX = -1, destY = -1;
    long destTime;
    double prevX, prevY, prevH, prevV;

    /** A round's brain with one gun (G_*) and one movement (M_*) on a field of that size. */
    public TechBrain(int gunKind, int moveKind, double fieldWidth, double fieldHeight) {
        this.gunKind = gunKind;
        this.moveKind = moveKind;
        this.fieldWidth = fieldWidth;
        this.fieldHeight = fieldHeight;
    }

    /** A round's start at (x, y): in the battle's first round, its generator and statistics start. */
    public static void startBattle(double x, double y) {
        if (rng == null) {
            // java.util.Random (seedable, unlike Math.random under Java 17) from the first round's start
            rng = new Random(Double.doubleToLongBits(x) * 31 + Double.doubleToLongBits(y));
            surf[MID] = 1;  // before any hit: expect head-on aim
        }
    }

    int slot(String name) {
        for (int k = 0; k < nE; k++) {
            if (eName[k].equals(name)) {
                return k;
            }
        }
        if (nE == MAXE) {
            return -1;
        }
        eName[nE] = name;
        return nE++;
    }

    /** A ScannedRobotEvent (the robot at (x, y) heading {@code heading} when it came). */
    public void onScanned(String name, double bearing, double distance, double enemyHeading, double enemyVelocity,
                          double enemyEnergy, long time, boolean mate, double x, double y, double heading) {
        int s = slot(name);
        if (s < 0) {
            return;
        }
        pex[s] = ex[s];
        pey[s] = ey[s];
        peh[s] = eh[s];
        pev[s] = ev[s];
        pee[s] = ee[s];
        ePrevScan[s] = eAlive[s] ? eScan[s] : -10;
        double b = heading + bearing;
        eb[s] = b;
        ed[s] = distance;
        ex[s] = x + StrictMath.sin(b) * ed[s];
        ey[s] = y + StrictMath.cos(b) * ed[s];
        eh[s] = enemyHeading;
        ev[s] = enemyVelocity;
        ee[s] = enemyEnergy;
        eScan[s] = time;
        eAlive[s] = true;
        eMate[s] = mate;
    }

    /** A RobotDeathEvent. */
    public void onRobotDeath(String name) {
        for (int k = 0; k < nE; k++) {
            if (eName[k].equals(name)) {
                eAlive[k] = false;
            }
        }
    }

    /** A HitByBulletEvent: the bullet's power and heading. */
    public void onHitByBullet(double power, double bulletHeading) {
        if (nHit < hitPower.length) {
            hitPower[nHit] = power;
            hitHeading[nHit++] = bulletHeading;
        }
    }

    /** A BulletHitEvent: our bullet's power. */
    public void onBulletHit(double p) {
        myHitDamage += 4 * p + (p > 1 ? 2 * (p - 1) : 0);  // Rules.getBulletDamage
    }

    /** After the turn's decision (made or not): this turn's bullet events are spent. */
    public void endTurn() {
        nHit = 0;
        myHitDamage = 0;
    }

    // ---- one decision ----

    /**
     * One decision (TechBot's turn) from the robot's state now, after the turn's events: the commands go to
     * {@link #cmd} (NaN = not set, fire 0 = none); set* semantics, the last value set wins.
     */
    public void decide(long now, double x, double y, double heading, double velocity, double energy,
                       double gunHeading, double gunHeat, double gunTurnRemaining, double radarHeading,
                       double radarTurnRemaining, int others) {
        this.heading = heading;
        this.velocity = velocity;
        this.energy = energy;
        this.gunHeading = gunHeading;
        this.gunHeat = gunHeat;
        this.gunTurnRemaining = gunTurnRemaining;
        for (int k = 0; k < 4; k++) {
            cmd[k] = Double.NaN;
        }
        cmd[4] = 0;
        aimSlot = -1;
        boolean duel = others <= 1 && moveKind != M_RISK;
        int t = target();
        boolean seen = t >= 0 && eScan[t] == now;
        if (seen && duel && !eMate[t]) {
            detectFire(t, now);
        }
        if (nHit > 0) {
            learnHits(x, y, now);
        }
        if (others <= 1) {
            if (seen) {
                cmd[3] = Utils.normalRelativeAngle(eb[t] - radarHeading) * 2;
            } else if (t < 0 || now - eScan[t] > 1) {
                cmd[3] = SPIN;
            }
        } else if (radarTurnRemaining < 1) {
            cmd[3] = SPIN;
        }
        if (t >= 0 && eAlive[t]) {
            if (!duel) {
                risk(x, y, now);
            } else if (moveKind == M_RAM) {
                cmd[1] = Utils.normalRelativeAngle(eb[t] - heading);
                cmd[0] = ed[t] + 40;
            } else if (moveKind == M_SURF) {
                surfMove(t, x, y, now);
            } else if (moveKind == M_STOPGO) {
                stopGo(t, x, y, now);
            } else {
                orbit(t, x, y, seen);
            }
            if (seen) {
                aimAndFire(t, x, y, now);
            }
        }
        prevX = x;
        prevY = y;
        prevH = heading;
        prevV = velocity;
    }

    /** The enemy to fight: the nearest alive non-team-mate (by its last scan). */
    int target() {
        int best = -1;
        for (int k = 0; k < nE; k++) {
            if (eAlive[k] && !eMate[k] && (best < 0 || ed[k] < ed[best])) {
                best = k;
            }
        }
        return best;
    }

    // ---- enemy fire and its statistics ----

    /** Energy drop between two consecutive scans, our hits on it and its hits on us removed: a wave. */
    void detectFire(int t, long now) {
        if (ePrevScan[t] != now - 1) {
            return;
        }
        double gained = 0;
        for (int k = 0; k < nHit; k++) {
            gained += 3 * hitPower[k];
        }
        double fired = pee[t] - ee[t] + gained - myHitDamage;
        if (fired < 0.0999 || fired > 3.0001) {
            return;
        }
        int w = -1;
        for (int k = 0; k < MAXW; k++) {
            if (!wOn[k]) {
                w = k;
                break;
            }
        }
        if (w < 0) {
            return;
        }
        wOn[w] = true;
        wx[w] = pex[t];
        wy[w] = pey[t];
        wt[w] = now - 1;
        ws[w] = 20 - 3 * fired;
        wa[w] = Math.atan2(prevX - wx[w], prevY - wy[w]);
        wd[w] = prevV * StrictMath.sin(prevH - wa[w]) >= 0 ? 1 : -1;
    }

    static double escape(double speed) {
        return Math.atan2(8, Math.sqrt(speed * speed - 64));  // asin(8 / speed)
    }

    static int bin(double g) {
        int k = (int) Math.floor((g + 1) * MID + 0.5);
        return Math.max(0, Math.min(BINS - 1, k));
    }

    /** Each bullet that hit us: the wave it rode (same speed, front nearest us) gives the GuessFactor it used. */
    void learnHits(double x, double y, long now) {
        for (int h = 0; h < nHit; h++) {
            double speed = 20 - 3 * hitPower[h];
            int best = -1;
            double bestGap = 60;
            for (int k = 0; k < MAXW; k++) {
                if (wOn[k] && Math.abs(ws[k] - speed) < 0.01) {
                    double gap = Math.abs(ws[k] * (now - wt[k]) - Math.hypot(x - wx[k], y - wy[k]));
                    if (gap < bestGap) {
                        bestGap = gap;
                        best = k;
                    }
                }
            }
            if (best >= 0) {
                double g = Utils.normalRelativeAngle(hitHeading[h] - wa[best]) / escape(ws[best]) * wd[best];
                int c = bin(g);
                for (int k = 0; k < BINS; k++) {
                    surf[k] += 1.0 / ((k - c) * (k - c) + 1);
                }
                wOn[best] = false;
            }
        }
    }

    // ---- movements ----

    static boolean inField(double px, double py, double w, double h) {
        return px >= MARGIN && px <= w - MARGIN && py >= MARGIN && py <= h - MARGIN;
    }

    /** Turn the wanted heading in steps of 0.05 rad until a point STICK ahead lies inside the field. */
    double smooth(double px, double py, double a, double dir) {
        double w = fieldWidth, h = fieldHeight;
        for (int k = 0; k < 60; k++) {
            if (inField(px + StrictMath.sin(a) * STICK, py + StrictMath.cos(a) * STICK, w, h)) {
                return a;
            }
            a += dir * 0.05;
        }
        return a;
    }

    /** Head for angle a, driving backwards when that is the shorter turn. */
    void goAngle(double a, double dist) {
        double turn = Utils.normalRelativeAngle(a - heading);
        if (Math.abs(turn) > HALF_PI) {
            cmd[1] = Utils.normalRelativeAngle(turn + Math.PI);
            cmd[0] = -dist;
        } else {
            cmd[1] = turn;
            cmd[0] = dist;
        }
    }

    /** Sideways to the enemy, a little toward it when far and away from it when near. */
    static double orbitAngle(double px, double py, double sx, double sy, double dist, double dir) {
        double attack = Math.max(-0.5, Math.min(0.5, (dist - 400) * 0.002));
        return Math.atan2(px - sx, py - sy) + dir * (HALF_PI + attack);
    }

    void orbit(int t, double x, double y, boolean seen) {
        if (seen && rng.nextDouble() < 0.05) {
            moveDir = -moveDir;
        }
        double a = orbitAngle(x, y, ex[t], ey[t], ed[t], moveDir);
        double s = smooth(x, y, a, moveDir);
        if (s != a && Math.abs(Utils.normalRelativeAngle(s - a)) > 1.2) {
            moveDir = -moveDir;  // cornered: smoothing turned us far around; go the other way
            s = smooth(x, y, orbitAngle(x, y, ex[t], ey[t], ed[t], moveDir), moveDir);
        }
        goAngle(s, 100);
    }

    void stopGo(int t, double x, double y, long now) {
        boolean fired = false;
        for (int k = 0; k < MAXW; k++) {
            if (wOn[k] && wt[k] == now - 1) {
                fired = true;
            }
        }
        double a = orbitAngle(x, y, ex[t], ey[t], ed[t], moveDir);
        if (fired) {
            if (rng.nextDouble() < 0.3 || !inField(x + StrictMath.sin(a) * 80, y + StrictMath.cos(a) * 80,
                    fieldWidth, fieldHeight)) {
                moveDir = -moveDir;
                a = orbitAngle(x, y, ex[t], ey[t], ed[t], moveDir);
            }
            goAngle(smooth(x, y, a, moveDir), 40);
        }
        expireWaves(x, y, now);
    }

    void expireWaves(double x, double y, long now) {
        for (int k = 0; k < MAXW; k++) {
            if (wOn[k] && ws[k] * (now - wt[k]) > Math.hypot(x - wx[k], y - wy[k]) + 50) {
                wOn[k] = false;
            }
        }
    }

    /** Wave surfing: for the wave that reaches us first, the least dangerous of orbiting either way or stopping. */
    void surfMove(int t, double x, double y, long now) {
        expireWaves(x, y, now);
        int w = -1;
        double soonest = 0;
        for (int k = 0; k < MAXW; k++) {
            if (wOn[k]) {
                double left = Math.hypot(x - wx[k], y - wy[k]) - ws[k] * (now - wt[k]);
                if (left > ws[k] && (w < 0 || left / ws[k] < soonest)) {
                    w = k;
                    soonest = left / ws[k];
                }
            }
        }
        if (w < 0) {
            goAngle(smooth(x, y, orbitAngle(x, y, ex[t], ey[t], ed[t], moveDir), moveDir), 100);
            return;
        }
        double here = danger(w, x, y, now, moveDir, ed[t]);
        double there = danger(w, x, y, now, -moveDir, ed[t]);
        double still = danger(w, x, y, now, 0, ed[t]);
        if (there < here) {
            moveDir = -moveDir;
            here = there;
        }
        if (still < here) {
            cmd[0] = 0;
            return;
        }
        goAngle(smooth(x, y, orbitAngle(x, y, wx[w], wy[w], ed[t], moveDir), moveDir), 100);
    }

    /** Precise prediction (accel 1, decel 2, turn 10 - 0.75|v| deg) of our path until wave w passes us. */
    double danger(int w, double x, double y, long now, double dir, double dist) {
        double px = x, py = y, ph = heading, pv = velocity;
        double fw = fieldWidth, fh = fieldHeight;
        for (int k = 1; k < 120; k++) {
            if (dir != 0) {
                double goal = smooth(px, py, orbitAngle(px, py, wx[w], wy[w], dist, dir), dir);
                double turn = Utils.normalRelativeAngle(goal - ph);
                double ahead = 1;
                if (StrictMath.cos(turn) < 0) {
                    turn = Utils.normalRelativeAngle(turn + Math.PI);
                    ahead = -1;
                }
                double maxTurn = (10 - 0.75 * Math.abs(pv)) * DEG;
                ph += Math.max(-maxTurn, Math.min(maxTurn, turn));
                pv = pv * ahead < 0 ? pv + 2 * ahead : Math.max(-8, Math.min(8, pv + ahead));
            } else {
                pv = pv > 0 ? Math.max(0, pv - 2) : Math.min(0, pv + 2);
            }
            px = Math.max(18, Math.min(fw - 18, px + StrictMath.sin(ph) * pv));
            py = Math.max(18, Math.min(fh - 18, py + StrictMath.cos(ph) * pv));
            if (ws[w] * (now + k - wt[w]) > Math.hypot(px - wx[w], py - wy[w]) - 18) {
                break;
            }
        }
        double g = Utils.normalRelativeAngle(Math.atan2(px - wx[w], py - wy[w]) - wa[w]) / escape(ws[w]) * wd[w];
        int c = bin(g);
        double d = surf[c];
        if (c > 0) {
            d += 0.5 * surf[c - 1];
        }
        if (c < BINS - 1) {
            d += 0.5 * surf[c + 1];
        }
        return d;
    }

    /** Minimum risk: every 12 turns or near the destination, the safest of ten random points around us. */
    void risk(double x, double y, long now) {
        double w = fieldWidth, h = fieldHeight;
        if (destX < 0 || now - destTime >= 12 || Math.hypot(destX - x, destY - y) < 20) {
            double best = destX < 0 ? Double.MAX_VALUE : riskAt(destX, destY, x, y);
            for (int k = 0; k < 10; k++) {
                double a = rng.nextDouble() * TWO_PI;
                double d = 80 + 120 * rng.nextDouble();
                double px = x + StrictMath.sin(a) * d, py = y + StrictMath.cos(a) * d;
                if (!inField(px, py, w - 15, h - 15) || px < 40 || py < 40) {
                    continue;
                }
                double r = riskAt(px, py, x, y);
                if (r < best) {
                    best = r;
                    destX = px;
                    destY = py;
                }
            }
            destTime = now;
        }
        if (destX >= 0) {
            goAngle(Math.atan2(destX - x, destY - y), Math.hypot(destX - x, destY - y));
        }
    }

    double riskAt(double px, double py, double x, double y) {
        double r = 0;
        double toP = Math.atan2(px - x, py - y);
        for (int k = 0; k < nE; k++) {
            if (eAlive[k]) {
                double dx = ex[k] - px, dy = ey[k] - py;
                double d2 = Math.max(dx * dx + dy * dy, 1);
                double along = 1 + Math.abs(StrictMath.cos(toP - Math.atan2(ex[k] - x, ey[k] - y)));
                r += (eMate[k] ? 50 : Math.min(ee[k], 100) + 20) * along / d2;
            }
        }
        double dx = px - x, dy = py - y;
        return r + 0.5 / Math.max(dx * dx + dy * dy, 1);
    }

    // ---- guns ----

    /** Where an enemy moving on with its heading turning by turnRate a turn meets a bullet of speed bs. */
    double predicted(int t, double x, double y, double bs, double turnRate) {
        double px = ex[t], py = ey[t], h = eh[t];
        double w = fieldWidth, fh = fieldHeight;
        for (int k = 1; k < 100; k++) {
            if (k * bs >= Math.hypot(px - x, py - y)) {
                break;
            }
            h += turnRate;
            px = Math.max(18, Math.min(w - 18, px + StrictMath.sin(h) * ev[t]));
            py = Math.max(18, Math.min(fh - 18, py + StrictMath.cos(h) * ev[t]));
        }
        return Math.atan2(px - x, py - y);
    }

    int segment(int t) {
        double lat = Math.abs(ev[t] * StrictMath.sin(eh[t] - eb[t]));
        int ds = Math.min(4, (int) (ed[t] / 150));
        int ls = lat < 2 ? 0 : lat < 5.5 ? 1 : 2;
        boolean consecutive = ePrevScan[t] == eScan[t] - 1;
        double a = consecutive ? Math.abs(ev[t]) - Math.abs(pev[t]) : 0;
        int as = a > 0 ? 2 : a < 0 ? 0 : 1;
        double s = ev[t] < 0 ? -1 : 1;
        int k = 0;
        while (k < 15 && inField(ex[t] + StrictMath.sin(eh[t]) * 20 * (k + 1) * s, ey[t] + StrictMath.cos(eh[t]) * 20 * (k + 1) * s,
                fieldWidth, fieldHeight)) {
            k++;
        }
        int wsg = k < 4 ? 0 : k < 10 ? 1 : 2;
        return ((ds * 3 + ls) * 3 + as) * 3 + wsg;
    }

    /** The fullest of the BINS counts from base (the first of equals; MID first). */
    static int peak(double[] counts, int base) {
        int best = MID;
        for (int k = 0; k < BINS; k++) {
            if (counts[base + k] > counts[base + best]) {
                best = k;
            }
        }
        return best;
    }

    void aimAndFire(int t, double x, double y, long now) {
        double power = Math.min(3, 1.2 + 300 / ed[t]);
        if (moveKind == M_RAM && ed[t] < 150) {
            power = 3;
        }
        if (energy < 15) {
            power = Math.min(power, 1);
        }
        power = Math.min(power, ee[t] / 4 + 0.1);
        power = Math.max(0.1, power);
        double bs = 20 - 3 * power;
        double lat = ev[t] * StrictMath.sin(eh[t] - eb[t]);
        if (lat > 0) {
            gunDir = 1;
        } else if (lat < 0) {
            gunDir = -1;
        }
        boolean consecutive = ePrevScan[t] == eScan[t] - 1;
        double turnRate = consecutive ? Utils.normalRelativeAngle(eh[t] - peh[t]) : 0;
        double mea = escape(bs);
        int seg = segment(t);
        // resolve the gun waves this enemy has passed: visit counts and virtual-gun hits
        for (int k = 0; k < MAXG; k++) {
            if (gOn[k] && gTarget[k] == t) {
                double d = Math.hypot(ex[t] - gx[k], ey[t] - gy[k]);
                if (gs[k] * (now - gt[k]) > d - 18) {
                    double actual = Math.atan2(ex[t] - gx[k], ey[t] - gy[k]);
                    double g = Math.max(-1, Math.min(1, Utils.normalRelativeAngle(actual - ga[k]) / gm[k] * gd[k]));
                    int c = bin(g);
                    int base = gSeg[k] * BINS;
                    gf[base + c] += 1;
                    if (c > 0) {
                        gf[base + c - 1] += 0.5;
                    }
                    if (c < BINS - 1) {
                        gf[base + c + 1] += 0.5;
                    }
                    base = gSeg[k] / 27 * BINS;
                    for (int j = 0; j < BINS; j++) {
                        asVisits[base + j] *= AS_DECAY;
                    }
                    asVisits[base + c] += 1;
                    if (c > 0) {
                        asVisits[base + c - 1] += 0.5;
                    }
                    if (c < BINS - 1) {
                        asVisits[base + c + 1] += 0.5;
                    }
                    double width = Math.atan2(18, d);
                    for (int q = 0; q < NGUNS; q++) {
                        double hit = Math.abs(Utils.normalRelativeAngle(gAim[k * NGUNS + q] - actual)) < width ? 1 : 0;
                        vgRate[q] = (vgRate[q] * 19 + hit) / 20;
                    }
                    double asHit = Math.abs(Utils.normalRelativeAngle(gAsAim[k] - actual)) < width ? 1 : 0;
                    asRate = (asRate * 19 + asHit) / 20;
                    gOn[k] = false;
                }
            }
        }
        // every gun's aim
        double head = eb[t];
        double linear = predicted(t, x, y, bs, 0);
        double circular = predicted(t, x, y, bs, turnRate);
        int best = peak(gf, seg * BINS);
        double guess = eb[t] + gunDir * (best - MID) / (double) MID * mea;
        int asBest = peak(asVisits, seg / 27 * BINS);
        double asGuess = eb[t] + gunDir * (asBest - MID) / (double) MID * mea;
        boolean antiSurf = gunKind == G_AS && asRate > vgRate[G_GF] + AS_MARGIN;
        double[] counts = antiSurf ? asVisits : gf;
        int base = antiSurf ? seg / 27 * BINS : seg * BINS;
        if (antiSurf) {
            best = asBest;
        }
        double total = 0;
        for (int q = 0; q < BINS; q++) {
            total += counts[base + q];
        }
        aimSlot = t;
        aimFactor = gunDir * (best - MID) / (double) MID;
        aimPeak = total > 0 ? counts[base + best] / total : 0;
        int k = gNext;
        gNext = (gNext + 1) % MAXG;
        gOn[k] = true;
        gx[k] = x;
        gy[k] = y;
        gt[k] = now;
        gs[k] = bs;
        ga[k] = eb[t];
        gd[k] = gunDir;
        gm[k] = mea;
        gSeg[k] = seg;
        gTarget[k] = t;
        gAim[k * NGUNS] = head;
        gAim[k * NGUNS + 1] = linear;
        gAim[k * NGUNS + 2] = circular;
        gAim[k * NGUNS + 3] = guess;
        gAsAim[k] = asGuess;
        int gun = gunKind;
        if (gun == G_VIRTUAL) {
            gun = G_CIRCULAR;
            for (int q = 0; q < NGUNS; q++) {
                if (vgRate[q] > vgRate[gun]) {
                    gun = q;
                }
            }
        } else if (gun == G_AS) {
            gun = G_GF;
        }
        double aim = antiSurf ? asGuess : gAim[k * NGUNS + gun];
        if (gunHeat == 0 && Math.abs(gunTurnRemaining) < 0.05 && energy > power + 0.1) {
            cmd[4] = power;
        }
        cmd[2] = Utils.normalRelativeAngle(aim - gunHeading);
    }

    // ---- what the brain knows about the battle (the tank view's knowledge block, confront.arena.tank) ----

    /** The enemy slot of a name this round (-1: never scanned). */
    public int slotOf(String name) {
        for (int k = 0; k < nE; k++) {
            if (eName[k].equals(name)) {
                return k;
            }
        }
        return -1;
    }

    /**
     * The knowledge block at (x, y) at time now, from the last decision: the four virtual guns' rolling hit
     * rates (head-on, linear, circular, GuessFactor), the enemy waves in the air (min(n, 4) / 4), the nearest
     * one's turns to reach us (min(t, 50) / 50; 1 without a wave), the share of the visits in the GuessFactor
     * bin of the last aim this round (0 without one), the share of the surfing danger in its peak bin.
     */
    public double[] knowledge(double x, double y, long now) {
        double[] k = new double[KNOWLEDGE];
        for (int q = 0; q < NGUNS; q++) {
            k[q] = vgRate[q];
        }
        int n = 0;
        double soonest = MAX_IMPACT;
        for (int w = 0; w < MAXW; w++) {
            if (wOn[w]) {
                n++;
                double left = (Math.hypot(x - wx[w], y - wy[w]) - ws[w] * (now - wt[w])) / ws[w];
                soonest = Math.min(soonest, Math.max(left, 0));
            }
        }
        k[4] = Math.min(n, 4) / 4.0;
        k[5] = soonest / MAX_IMPACT;
        k[6] = aimPeak;
        double top = 0, total = 0;
        for (int q = 0; q < BINS; q++) {
            top = Math.max(top, surf[q]);
            total += surf[q];
        }
        k[7] = total > 0 ? top / total : 0;
        return k;
    }

    /** The gun's absolute angle of the last decision's GuessFactor aim at a bullet of that power (NaN: no aim at
     *  that slot this turn). */
    public double guessAim(int slot, double power) {
        if (slot < 0 || slot != aimSlot) {
            return Double.NaN;
        }
        return eb[slot] + aimFactor * escape(20 - 3 * power);
    }
}
