package confront.tech;

/** Wave surfing; GuessFactor gun with an anti-surfer GuessFactor gun beside it (the one that hits more). */
public class SurfAS extends TechBot {
    public SurfAS() {
        super(G_AS, M_SURF);
    }
}
