package confront.tech;

/** Wave surfing; GuessFactor gun. */
public class SurfGF extends TechBot {
    public SurfGF() {
        super(G_GF, M_SURF);
    }
}
