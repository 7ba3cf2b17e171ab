package confront.tech;

/** Random orbit with wall smoothing; circular gun. */
public class OrbitCircular extends TechBot {
    public OrbitCircular() {
        super(G_CIRCULAR, M_ORBIT);
    }
}
