package confront.tech;

/** Random orbit with wall smoothing; linear gun. */
public class OrbitLinear extends TechBot {
    public OrbitLinear() {
        super(G_LINEAR, M_ORBIT);
    }
}
