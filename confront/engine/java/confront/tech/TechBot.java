package confront.tech;

import robocode.BulletHitEvent;
import robocode.DeathEvent;
import robocode.HitByBulletEvent;
import robocode.RobotDeathEvent;
import robocode.ScannedRobotEvent;
import robocode.TeamRobot;

/**
 * The classic Robocode techniques, one gun and one movement per robot (each subclass picks two): a robot around
 * a {@link TechBrain}, which makes its decisions.
 *
 * One decision per turn in run() (event handlers only record: they hand the events to the brain), then the
 * brain's commands as set* calls and execute(). The brain's battle memory lives in its static fields (one class
 * load per battle).
 */
public abstract class TechBot extends TeamRobot {
    static final int G_HEAD = TechBrain.G_HEAD, G_LINEAR = TechBrain.G_LINEAR, G_CIRCULAR = TechBrain.G_CIRCULAR,
            G_GF = TechBrain.G_GF, G_VIRTUAL = TechBrain.G_VIRTUAL, G_AS = TechBrain.G_AS;
    static final int M_ORBIT = TechBrain.M_ORBIT, M_STOPGO = TechBrain.M_STOPGO, M_RAM = TechBrain.M_RAM,
            M_SURF = TechBrain.M_SURF, M_RISK = TechBrain.M_RISK;

    private final int gunKind, moveKind;
    private TechBrain brain;
    // set by onDeath: a dead robot decides nothing more (the engine may still wake it, e.g. when a bullet it fired
    // hits after its death and gives it energy: a race between the battle thread and the robot's)
    private boolean dead;

    protected TechBot(int gunKind, int moveKind) {
        this.gunKind = gunKind;
        this.moveKind = moveKind;
    }

    private TechBrain brain() {
        if (brain == null) {
            brain = new TechBrain(gunKind, moveKind, getBattleFieldWidth(), getBattleFieldHeight());
        }
        return brain;
    }

    @Override
    public void run() {
        setAdjustGunForRobotTurn(true);
        setAdjustRadarForRobotTurn(true);
        setAdjustRadarForGunTurn(true);
        TechBrain.startBattle(getX(), getY());
        TechBrain b = brain();
        setTurnRadarRightRadians(TechBrain.SPIN);
        while (true) {
            if (!dead) {
                b.decide(getTime(), getX(), getY(), getHeadingRadians(), getVelocity(), getEnergy(),
                        getGunHeadingRadians(), getGunHeat(), getGunTurnRemainingRadians(), getRadarHeadingRadians(),
                        getRadarTurnRemainingRadians(), getOthers());
                double[] c = b.cmd;
                if (!Double.isNaN(c[0])) {
                    setAhead(c[0]);
                }
                if (!Double.isNaN(c[1])) {
                    setTurnRightRadians(c[1]);
                }
                if (!Double.isNaN(c[2])) {
                    setTurnGunRightRadians(c[2]);
                }
                if (!Double.isNaN(c[3])) {
                    setTurnRadarRightRadians(c[3]);
                }
                if (c[4] > 0) {
                    setFire(c[4]);
                }
            }
            b.endTurn();
            execute();
        }
    }

    @Override
    public void onScannedRobot(ScannedRobotEvent e) {
        brain().onScanned(e.getName(), e.getBearingRadians(), e.getDistance(), e.getHeadingRadians(),
                e.getVelocity(), e.getEnergy(), getTime(), isTeammate(e.getName()), getX(), getY(),
                getHeadingRadians());
    }

    @Override
    public void onDeath(DeathEvent e) {
        dead = true;
    }

    @Override
    public void onRobotDeath(RobotDeathEvent e) {
        brain().onRobotDeath(e.getName());
    }

    @Override
    public void onHitByBullet(HitByBulletEvent e) {
        brain().onHitByBullet(e.getBullet().getPower(), e.getBullet().getHeadingRadians());
    }

    @Override
    public void onBulletHit(BulletHitEvent e) {
        brain().onBulletHit(e.getBullet().getPower());
    }
}
