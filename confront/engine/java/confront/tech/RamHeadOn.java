package confront.tech;

/** Ramming; head-on gun. */
public class RamHeadOn extends TechBot {
    public RamHeadOn() {
        super(G_HEAD, M_RAM);
    }
}
