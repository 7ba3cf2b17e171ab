package confront.tech;

/** Stop-and-go; circular gun. */
public class StopGoCircular extends TechBot {
    public StopGoCircular() {
        super(G_CIRCULAR, M_STOPGO);
    }
}
