package confront.tech;

/** Wave surfing; virtual guns (head-on, linear, circular, GuessFactor). */
public class SurfVG extends TechBot {
    public SurfVG() {
        super(G_VIRTUAL, M_SURF);
    }
}
