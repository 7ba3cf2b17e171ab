package confront.tech;

/** Random orbit with wall smoothing; virtual guns. */
public class OrbitVG extends TechBot {
    public OrbitVG() {
        super(G_VIRTUAL, M_ORBIT);
    }
}
