package confront.tech;

/** Minimum-risk movement (melee and teams); GuessFactor gun. */
public class RiskGF extends TechBot {
    public RiskGF() {
        super(G_GF, M_RISK);
    }
}
