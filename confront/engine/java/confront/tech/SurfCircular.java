package confront.tech;

/** Wave surfing; circular gun. */
public class SurfCircular extends TechBot {
    public SurfCircular() {
        super(G_CIRCULAR, M_SURF);
    }
}
