package confront.tech;

/** Random orbit with wall smoothing; GuessFactor gun. */
public class OrbitGF extends TechBot {
    public OrbitGF() {
        super(G_GF, M_ORBIT);
    }
}
