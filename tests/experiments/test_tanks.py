"""PPO tanks: the tank view's hand-computed entries, a short training run that learns, exact resume."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from confront import checkpoint as ck
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.tank import OWN_FEATURES, TankSpace, action_table, lead_point, tank_view_row
from confront.experiments.tank_evaluate import evaluate_tanks
from confront.runs import Run
from confront.train.factory import train_run
from confront.train.loop import new_run, share_by_opponent
from confront.train.ppo_sim import TankTrainer
from confront.train.spec import load_experiment


def test_view_hand_computed() -> None:
    # robot 0 at (100, 100) heading east; enemy 1 last scanned at (100, 400) (north of it), 3 turns ago,
    # heading west at 8 px/turn, energy 50 after 80 (a drop of 30 > 3: clipped); mate 2 at (400, 100)
    x, y = np.array([100.0, 300.0, 400.0]), np.array([100.0, 300.0, 100.0])
    h = np.array([math.pi / 2, 0.0, 0.0])
    mem = np.zeros((9, 3, 3))
    mem[:, 0, 1] = [100.0, 400.0, 50.0, 3 * math.pi / 2, 8.0, 30.0, 1.0, 0.0, 7.0]
    seen = np.full((3, 3), -1, dtype=np.int32)
    seen[0, 1] = 7
    out, slots = np.zeros(11 + 9 * 2 + 5), np.zeros(2, dtype=np.int64)
    tank_view_row(x, y, h, np.array([-4.0, 0, 0]), np.array([60.0, 80, 90]), np.array([1.5, 0, 0]),
                  np.ones(3, bool), np.array([0, 1, 0]), 0, mem, seen, 10.0, 800.0, 600.0, 2, 1,
                  np.stack([x, y, [60, 80, 90.0]]), True, out, slots, np.empty(3))
    np.testing.assert_allclose(out[:11], [100 / 800, 100 / 600, 700 / 800, 500 / 600, 1.0, math.cos(math.pi / 2),
                                          -0.5, 0.6, 0.5, 1.0, 1.0], atol=1e-12)
    e = out[OWN_FEATURES:OWN_FEATURES + 9]
    # bearing north = -90 deg from an east heading; moving west = lateral -(8)/8 (anticlockwise around us)
    np.testing.assert_allclose(e, [1.0, -1.0, 0.0, 300 / 1000, -1.0, 0.0, 0.5, 3 / 50, 1.0], atol=1e-12)
    assert slots.tolist() == [1, -1] and (out[20:29] == 0).all()
    np.testing.assert_allclose(out[29:], [1.0, 0.0, 1.0, 300 / 1000, 0.9], atol=1e-12)  # mate straight ahead


def test_lead_point_linear_and_circular() -> None:
    # a target 200 px north moving east at 8 px/turn, scanned now; power 3 bullets fly 11 px/turn
    px, py = lead_point(400.0, 100.0, 400.0, 300.0, math.pi / 2, 8.0, 0.0, 0.0, 3.0, 800.0, 600.0)
    t = math.hypot(px - 400, py - 100) / 11.0
    assert py == pytest.approx(300.0) and px == pytest.approx(400 + 8 * t, rel=1e-3)  # 10 fixed-point steps
    # turning: after tau turns on the circle of radius v / w
    w = math.radians(5)
    cx, cy = lead_point(400.0, 100.0, 400.0, 300.0, math.pi / 2, 8.0, w, 0.0, 3.0, 800.0, 600.0)
    tau = math.hypot(cx - 400, cy - 100) / 11.0
    assert cx == pytest.approx(400 + 8 / w * (math.cos(math.pi / 2) - math.cos(math.pi / 2 + w * tau)), rel=1e-3)
    assert cy == pytest.approx(300 + 8 / w * (math.sin(math.pi / 2 + w * tau) - 1.0), rel=1e-3) and cy < 300


def test_action_table_decodes_the_heads() -> None:
    space = TankSpace()
    table = action_table(space)
    a = np.ravel_multi_index((4, 0, 0, 2, 1), space.dims)
    np.testing.assert_allclose(table[a], [150.0, math.radians(-90.0), -1.0, 2.0, 1.0, 2.0, 0.0])  # hold: -1, circ.: 2
    assert table[a - 1, 5] == 0.0 and len(table) == 5 * 5 * 4 * 4 * 2


def test_hold_fire_never_fires_and_the_slot_picks_the_target() -> None:
    space = TankSpace(fire_powers=(0.0,), distances=(0.0,), turns_deg=(0.0,), leads=("none",))
    env = TeamBattleEnv("4v4", n_battles=2, seed=1, opponents="SittingDuck",
                        config=SMDPConfig(turns_per_step=5, tank=space, reward="score"))
    env.reset()
    start = env.arena.state.energy.copy()  # the team leaders start with 200
    slots_seen = 0
    for step in range(20):
        k = step % space.enemy_slots
        before = env.slots.copy()
        env.step(np.full((2, 8), k, dtype=np.int64))  # joint action = the slot (the other heads have one choice)
        np.testing.assert_array_equal(env._chosen[:, :4], before[:, :4, k])
        slots_seen += int((before[:, :4, k] >= 4).sum())
    assert slots_seen > 0
    np.testing.assert_array_equal(env.arena.state.energy, start)  # nobody fired, nobody was hit


def _cfg(tmp_path, opponents: str, **kw: str) -> object:
    ov = ['learner.kind="ppo"', f"league.opponents={json.dumps(opponents.split(','))}", "ppo.rollout_steps=16",
          "train.session_rounds=8", f"train.checkpoint_every={kw.pop('ckpt', 1000)}", "ppo.hidden=32"]
    ov += [f"{k}={v}" for k, v in kw.items()]
    return load_experiment("demo", ov)


@pytest.mark.parametrize("overlap", ["false", "true"])
def test_training_against_sittingduck_learns(tmp_path, overlap: str) -> None:
    # with overlap the tanks act one update behind (decoupled PPO): it must learn about as fast
    cfg = _cfg(tmp_path, "1v1:SittingDuck", **{"league.battles": "16", "train.rounds": "200", "ppo.lr": "0.002",
                                                "ppo.overlap": overlap})
    trainer = TankTrainer(cfg)
    before = evaluate_tanks(cfg, trainer.ppo, rounds=8)["1v1:SittingDuck"]
    while trainer.rounds_done < 200:
        trainer.update()
    after = evaluate_tanks(cfg, trainer.ppo, rounds=8)["1v1:SittingDuck"]
    turns_first = np.mean([r["turns"] for r in trainer.rows[:32]])
    turns_last = np.mean([r["turns"] for r in trainer.rows[-32:]])
    assert after["share"] > 0.9 and after["win_rate"] == 1.0
    assert turns_last < 0.85 * turns_first  # it learned to destroy the sitting duck sooner
    assert before["win_rate"] <= after["win_rate"]


def test_training_with_skills_against_a_technique_robot_raises_its_share(tmp_path) -> None:
    # RamHeadOn (ramming, head-on gun, battle memory over 35-round battles): the tank with the skills (gf lead,
    # surf, the knowledge block) starts near 0.3 and must learn to keep away and hit it within 300 rounds
    cfg = _cfg(tmp_path, "1v1:RamHeadOn", **{"league.battles": "16", "train.rounds": "300", "ppo.lr": "0.002",
                                             "tank.leads": '["none","gf"]', "tank.surf": "true",
                                             "tank.knowledge": "true"})
    trainer = TankTrainer(cfg)
    before = evaluate_tanks(cfg, trainer.ppo, rounds=16)["1v1:RamHeadOn"]["share"]
    while trainer.rounds_done < 300:
        trainer.update()
    after = evaluate_tanks(cfg, trainer.ppo, rounds=16)["1v1:RamHeadOn"]["share"]
    share = [r["score_ours"] / max(r["score_ours"] + r["score_theirs"], 1e-9) for r in trainer.rows]
    assert after > 0.6 and after > before + 0.3
    assert np.mean(share[-32:]) > np.mean(share[:32]) + 0.2  # it rose in training too, not only greedily


@pytest.mark.parametrize(("overlap", "prioritise"), [("false", "false"), ("true", "false"), ("false", "true")])
def test_resume_after_a_kill_is_exact(tmp_path, overlap: str, prioritise: str) -> None:
    cfg = _cfg(tmp_path, "1v1:SpinBot,4v4:dodge", ckpt="6", **{"league.battles": "2", "train.rounds": "14",
                                                              "ppo.overlap": overlap,
                                                              "league.prioritise": prioritise})
    full = train_run(cfg, tmp_path / "full", progress=False)
    part = new_run(cfg, tmp_path / "part")
    part.release()  # the "killed" process's lock
    trainer = TankTrainer(cfg)
    while trainer.rounds_done < 6:
        trainer.update()
    arrays, meta = trainer.state()
    ck.save(part.checkpoints, f"round-{trainer.rounds_done:06d}", arrays, meta)  # then the process "dies"
    resumed = train_run(None, part.path, resume=True, progress=False)
    assert resumed["rounds"] == full["rounds"]
    a, b = Run(tmp_path / "full").read_table("rounds"), Run(tmp_path / "part").read_table("rounds")
    assert [r["score_ours"] for r in a] == [r["score_ours"] for r in b]
    wa = np.load(tmp_path / "full" / "model" / "actor.npz")
    wb = np.load(tmp_path / "part" / "model" / "actor.npz")
    for k in wa.files:
        np.testing.assert_array_equal(wa[k], wb[k])
    assert set(share_by_opponent(a)) == {"1v1:SpinBot", "4v4:dodge"}


def test_report_targets_and_intervals() -> None:
    from confront.experiments.tank_report import mean_interval, target_of

    assert target_of("1v1:Walls") == 0.90 and target_of("4v4:Crazy") == 0.80
    assert target_of("1v1:SurfGF") == 0.60 and target_of("4v4:RiskGF") == 0.70  # the technique robots
    assert target_of("4v4:td") == 0.75 and target_of("4v4:dodge") == 0.65 and target_of("1v1:self") is None
    m, lo, hi = mean_interval([0.8, 0.9, 1.0])
    assert m == pytest.approx(0.9) and lo == pytest.approx(0.9 - 4.302653 * 0.1 / math.sqrt(3), rel=1e-5)
    assert math.isnan(mean_interval([0.5])[1])


def test_compare_entries_and_paired_verdicts(tmp_path) -> None:
    from confront.experiments.tank_compare import METHODS, OURS, compare_entries, write_markdown

    league = ("1v1:SpinBot", "1v1:dodge", "1v1:self", "4v4:td", "1v1:td", "4v4:Walls", "4v10:SpinBot")
    assert compare_entries(league) == ["1v1:SpinBot", "1v1:dodge", "4v4:td", "4v4:Walls"]
    # 5 seeds, ours ahead of every method by 0.1 on each: the sign-flip p is 1/32 (all 32 flips enumerated)
    from confront.stats import paired_comparison

    ours = np.array([0.9, 0.8, 0.85, 0.95, 0.7])
    pc = paired_comparison(ours, ours - 0.1, np.random.default_rng(0))
    assert pc.diff.mean == pytest.approx(0.1) and pc.p == pytest.approx(1 / 32, abs=0.01)
    entries = ["1v1:SpinBot", "4v4:td"]
    shares = {m: {e: list(ours - (0.1 if m != OURS else 0.0)) for e in entries} for m in (OURS, *METHODS)}
    tests = {m: {"1v1:SpinBot": {"diff": 0.1, "lo": 0.1, "hi": 0.1, "p": 1 / 32},
                 "4v4:td": {"diff": 0.1, "lo": -0.1, "hi": 0.3, "p": 0.2}} for m in METHODS}
    md = write_markdown({"seeds": [0, 1, 2, 3, 4], "rounds": 10, "train_rounds": 500, "entries": entries,
                         "shares": shares, "tests": tests}, tmp_path).read_text()
    assert "| 1v1:SpinBot | 0.840 | 0.740 |" in md
    assert f"{METHODS[0]} on 1 of 2 entries" in md


def test_welch_comparison_hand_computed() -> None:
    from confront.experiments.tank_compare import welch_greater

    # a = (0.9, 0.92, 0.91), b = (0.5, 0.6, 0.55, 0.52, 0.58): diff 0.36; s_a^2 = 1e-4, s_b^2 = 1.7e-3
    # se = sqrt(1e-4/3 + 1.7e-3/5) = 0.019322, t = 18.63, Welch df = 4.6: one-sided p ~ 6.5e-6
    w = welch_greater([0.9, 0.92, 0.91], [0.5, 0.6, 0.55, 0.52, 0.58])
    assert w["diff"] == pytest.approx(0.36) and w["p"] == pytest.approx(6.53e-6, rel=0.01)
    assert w["lo"] < 0.36 < w["hi"] and w["hi"] - 0.36 == pytest.approx(0.36 - w["lo"])
    assert welch_greater([1.0, 1.0], [1.0, 1.0, 1.0])["p"] == 1.0  # a tie at the ceiling is not a win


def test_demo_contrast_windows_and_figure(tmp_path) -> None:
    from confront.experiments.demo import plot_contrast
    from confront.train.loop import share_windows

    rows = [{"opponent": "4v4:td", "score_ours": 3.0 * (k >= 10), "score_theirs": 1.0} for k in range(20)]
    assert share_windows(rows, 10) == [(10, 0.0), (20, 0.75)]
    assert share_windows(rows[:19], 10) == [(10, 0.0)]  # a partial last window is dropped
    Run(tmp_path / "tanks").write_table("rounds", rows + [{"opponent": "1v1:SpinBot", "score_ours": 9.0,
                                                          "score_theirs": 0.0}])
    Run(tmp_path / "paper").write_table("rounds", [{"score_ours": 1.0, "score_theirs": 1.0}] * 30)
    fig = plot_contrast(tmp_path / "tanks", tmp_path / "paper")
    assert fig == tmp_path / "tanks" / "plots" / "contrast.png" and fig.stat().st_size > 5000


@pytest.mark.parametrize(("override", "message"), [
    ('league.opponents=["1v1:nope"]', "league.opponents entry '1v1:nope'"),
    ('league.opponents=["1v1:MyFirstTeam"]', "'1v1:MyFirstTeam' is not allowed: MyFirstTeam needs teams of 2"),
    ('tank.leads=["sideways"]', "tank.leads entry 'sideways'"),
    ("tank.fire_powers=[0.05]", "tank.fire_powers"),
    ('league.focus=["1v1:SpinBot*x"]', "the weight after '*' must be an integer in 1..64"),
])
def test_bad_tank_configs_are_one_line_errors(tmp_path, override: str, message: str) -> None:
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "confront.cli.main", "train", "-c", "tanks", "--set", override,
                           "--out", str(tmp_path / "run")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "run").exists()


def test_focus_weights_per_entry() -> None:
    league = load_experiment("tanks", ['league.focus=["4v4:td", "1v1:SpinBot*2"]', "league.battles=5",
                                       "league.focus_weight=3"]).league
    assert [league.battles_of(e) for e in ("4v4:td", "1v1:SpinBot", "1v1:Walls")] == [15, 10, 5]


def test_polyak_average_is_a_config_key() -> None:
    from confront.config import ConfigError

    assert load_experiment("tanks-demo", ["ppo.ema_decay=0.95"]).ppo.ema_decay == 0.95
    assert load_experiment("tanks-demo").ppo.ema_decay == 0.0  # off unless a config asks for it
    with pytest.raises(ConfigError, match="ema_decay"):
        load_experiment("tanks-demo", ["ppo.ema_decay=1.0"])


def test_report_engine_over_runs(tmp_path) -> None:
    """--engine-runs: per entry the mean of the runs' engine means with its t-interval, and how many runs meet."""
    from confront.experiments.tank_report import write_markdown

    trained = [{"rounds": 10, "wall_time_s": 1.0, "decisions": 100}] * 3
    result = {"runs": ["a", "b", "c"], "rounds": 10, "engine_seeds": 2, "trained": trained,
              "engine_runs": ["a", "b", "c"], "unseen": [],
              "rows": [{"entry": "1v1:Walls", "sim": [0.9, 0.95, 0.85], "engine": [0.92, 0.94],
                        "engine_runs": [[0.92, 0.94], [0.88, 0.90], [0.95, 0.97]], "target": 0.90},
                       {"entry": "1v1:self", "sim": [0.5, 0.5, 0.5], "engine": None, "engine_runs": None,
                        "target": None}]}
    md = write_markdown(result, tmp_path).read_text()
    m = (0.93 + 0.89 + 0.96) / 3  # the runs' means
    half = 4.302653 * math.sqrt(((0.93 - m) ** 2 + (0.89 - m) ** 2 + (0.96 - m) ** 2) / 2 / 3)  # t(0.975, 2) sem
    row = next(line for line in md.splitlines() if line.startswith("| 1v1:Walls"))
    assert f"| {m:.3f} [{m - half:.3f}, {m + half:.3f}] | 2/3 |" in row and row.endswith("| 0.90 | yes |")
    assert "| engine, 3 runs | runs met |" in md and "Engine, 3 runs (a, b, c)" in md
    assert next(line for line in md.splitlines() if line.startswith("| 1v1:self")).endswith("| - | | - | |")
    assert "Simulator: the greedy policy" in md and "playing greedy" in md  # results without "play": greedy
    md = write_markdown({**result, "play": "sampled"}, tmp_path).read_text()
    assert "Simulator: the sampled policy" in md and "(no Python; playing sampled)" in md


def test_paper_move_values_have_the_opponents_choices_as_maxima() -> None:
    """The tables the engine's PolicyBot plays (random ties) draw from the moves the simulator's opponents do."""
    from confront.arena.observe import N_STATES
    from confront.train.league import dodge_policy, paper_move_values
    from confront.train.spec import load_experiment

    cfg = load_experiment("tanks-demo")
    disc = np.repeat(np.arange(N_STATES), 64)
    drawn = dodge_policy(disc, np.zeros((len(disc), 1)), np.random.default_rng(0)).reshape(N_STATES, 64)
    q = paper_move_values(cfg, "dodge")
    for s in range(N_STATES):
        assert set(np.flatnonzero(q[s] == q[s].max())) == set(drawn[s].tolist())
    assert (paper_move_values(cfg, "random") == 0).all()  # every move a maximum: uniform
    with pytest.raises(ValueError, match="paper-move"):
        paper_move_values(cfg, "SpinBot")


def test_evaluate_cli_samples_by_default_and_plays_greedy_on_request(tmp_path) -> None:
    from click.testing import CliRunner

    from confront.cli.main import cli
    from confront.train.ppo_model import load_tank_model

    cfg = _cfg(tmp_path, "1v1:SpinBot", **{"league.battles": "2", "train.rounds": "8"})
    train_run(cfg, tmp_path / "run", progress=False)
    ppo = load_tank_model(tmp_path / "run", cfg)
    for args, explore in (([], True), (["--play", "greedy"], False)):
        res = CliRunner().invoke(cli, ["evaluate", str(tmp_path / "run"), "--rounds", "6", "--seed", "3", *args])
        assert res.exit_code == 0, res.output
        assert ("sampled policy" if explore else "greedy policy") in res.output
        want = evaluate_tanks(cfg, ppo, rounds=6, seed=3, explore=explore)["1v1:SpinBot"]
        assert f"| 1v1:SpinBot | {want['rounds']} | {want['share']:.3f} | {want['win_rate']:.2f} |" in res.output


def test_baseline_cache_is_kept_per_td_team(tmp_path) -> None:
    from confront.experiments.baselines import RANDOM_METHOD
    from confront.experiments.tank_compare import method_shares

    entries = ["1v1:SittingDuck"]
    played = method_shares(RANDOM_METHOD, 0, entries, "/a/td/aaaa", 2, tmp_path)["1v1:SittingDuck"]
    cache = tmp_path / "results" / "Random_moves-seed-0.json"
    got = json.loads(cache.read_text())
    assert got["td_team"] == "aaaa" and got["shares"]["1v1:SittingDuck"] == played
    cache.write_text(json.dumps({**got, "shares": {"1v1:SittingDuck": 0.123}}))
    # the same artefact on another machine's path: the cache; another TD team: played again
    assert method_shares(RANDOM_METHOD, 0, entries, "/b/td/aaaa", 2, tmp_path)["1v1:SittingDuck"] == 0.123
    assert method_shares(RANDOM_METHOD, 0, entries, "/a/td/bbbb", 2, tmp_path)["1v1:SittingDuck"] == played
    assert json.loads(cache.read_text())["td_team"] == "bbbb"


def test_engine_comparison_caches_each_battle_and_plays_the_td_team_as_policybots(tmp_path, monkeypatch) -> None:
    from confront.engine import evaluate as engine_evaluate
    from confront.experiments.baselines import RANDOM_METHOD
    from confront.experiments.tank_compare import engine_method_shares
    from confront.learning.tabular import TabularQ
    from confront.train.paper_model import save_model

    td = tmp_path / "td" / "abcd"
    save_model(td, TabularQ(), {})
    played = []

    def battle(policy, scenario, opponents, rounds=100, seed=0, opponent_policy=None):  # noqa: ANN001, ANN202
        played.append({"policy": policy, "entry": f"{scenario}:{opponents}", "rounds": rounds, "seed": seed,
                       "theirs": opponent_policy})
        return None, 0.25 + 0.01 * len(played)

    monkeypatch.setattr(engine_evaluate, "evaluate_policy", battle)
    entries, work = ["1v1:SpinBot", "4v4:td"], tmp_path / "work"
    got = engine_method_shares(RANDOM_METHOD, 0, entries, str(td), 3, work)
    assert got == {"1v1:SpinBot": 0.26, "4v4:td": 0.27}
    spin, team = played
    assert (spin["entry"], spin["rounds"], spin["seed"], spin["theirs"]) == ("1v1:SpinBot", 3, 1, None)
    ours = spin["policy"]  # random moves: zero move values, random ties, the baselines' T = 10
    assert ours.kind == "qtable" and not ours.q.any() and ours.ties == "random" and ours.step_turns == 10
    theirs = team["theirs"]  # the TD team: its table, greedy with random ties, at the baselines' step length
    assert theirs.kind == "qtable" and theirs.ties == "random" and theirs.step_turns == 10
    np.testing.assert_array_equal(theirs.q, TabularQ().state_dict()["q"])
    assert engine_method_shares(RANDOM_METHOD, 0, entries, "/elsewhere/td/abcd", 3, work) == got  # cached
    assert len(played) == 2
    cache = work / "engine" / "Random_moves-seed-0.json"
    kept = json.loads(cache.read_text())
    assert kept["td_team"] == "abcd" and kept["engine_seed"] == 1 and kept["rounds"] == 3
    del kept["shares"]["4v4:td"]  # a comparison stopped after its first battle plays only the missing one
    cache.write_text(json.dumps(kept))
    assert engine_method_shares(RANDOM_METHOD, 0, entries, str(td), 3, work)["4v4:td"] == 0.28
    assert [b["entry"] for b in played] == ["1v1:SpinBot", "4v4:td", "4v4:td"]
    engine_method_shares(RANDOM_METHOD, 0, entries, str(td), 4, work)  # other rounds: every battle again
    assert len(played) == 5


def test_engine_comparison_pairs_each_seed_with_the_reports_engine_mean(tmp_path, monkeypatch) -> None:
    from confront.experiments import tank_compare as tc
    from confront.train import league

    entries = ["1v1:SittingDuck", "1v1:dodge", "4v4:td"]
    ours = {e: [[0.5 + 0.1 * k, 0.6 + 0.1 * k, 0.7 + 0.1 * k] for k in range(5)] for e in entries}
    ours["1v1:SittingDuck"] = [[1.0] * 3] * 5
    rep = {"runs": [f"seed{k}" for k in range(5)], "engine_runs": [f"seed{k}" for k in range(5)], "rounds": 100,
           "engine_seeds": 3, "play": "sampled", "rows": [{"entry": e, "engine_runs": ours[e]} for e in entries]}
    (tmp_path / "results.json").write_text(json.dumps(rep))
    calls = []

    def shares(method, seed, entries, td_model, rounds, work, engine_seed):  # noqa: ANN001, ANN202
        calls.append((method, seed, td_model, rounds, engine_seed))
        # 0.1 below PPO tanks' mean at every seed
        return {"1v1:SittingDuck": 1.0, "1v1:dodge": 0.5 + 0.1 * seed, "4v4:td": 0.5 + 0.1 * seed}

    monkeypatch.setattr(tc, "engine_method_shares", shares)
    monkeypatch.setattr(league, "td_team", lambda cfg, n: (None, Path(f"/c/td/t{cfg.train.seed}")))
    res = tc.compare_engine(tmp_path / "results.json", tmp_path / "out", 7, tmp_path / "work")
    assert res["seeds"] == [0, 1, 2, 3, 4] and res["entries"] == ["1v1:SittingDuck", "1v1:dodge", "4v4:td"]
    assert calls[:3] == [(m, 0, "/c/td/t0", 7, 1) for m in tc.METHODS] and len(calls) == 15
    assert res["shares"][tc.OURS]["4v4:td"] == pytest.approx([0.6 + 0.1 * k for k in range(5)])
    for m in tc.METHODS:
        assert res["tests"][m]["4v4:td"]["diff"] == pytest.approx(0.1)
        assert res["tests"][m]["4v4:td"]["p"] == pytest.approx(1 / 32, abs=0.01)
        assert res["tests"][m]["1v1:SittingDuck"]["diff"] == 0.0 and res["tests"][m]["1v1:SittingDuck"]["p"] == 1
    assert json.loads((tmp_path / "out" / "compare-engine.json").read_text())["engine"] == {
        "engine_seed": 1, "ours_rounds": 100, "ours_battles": 3, "ours_play": "sampled"}
    md = (tmp_path / "out" / "compare-engine.md").read_text()
    assert "the mean of 3 battles x 100 rounds (engine seeds 1-3)" in md
    assert "1 battle x 7 rounds (engine seed 1)" in md
    assert "| 4v4:td | 0.800 | 0.700 | 0.700 | 0.700 |" in md and "DMNN (FLM) on 2 of 3 entries" in md
    assert not (tmp_path / "out" / "compare.md").exists()
    assert tc.run_seed("seed3") == 3 and tc.run_seed("runs/tanks-seed-12") == 12
    with pytest.raises(ValueError, match="training seed"):
        tc.run_seed("shipped")


def test_the_baselines_face_the_dodge_as_its_own_policy_draws() -> None:
    from confront.experiments.tank_compare import dodge_learner
    from confront.train.league import dodge_policy

    states = np.repeat(np.arange(320), 200)
    ours = dodge_learner(load_experiment("tanks", ())).act(states, np.random.default_rng(1), explore=False)
    theirs = dodge_policy(states, np.zeros((len(states), 1)), np.random.default_rng(2))
    # the same two moves in each state, each drawn about half the time
    c_ours = np.stack([np.bincount(ours[states == s], minlength=4) for s in range(320)])
    c_theirs = np.stack([np.bincount(theirs[states == s], minlength=4) for s in range(320)])
    assert np.array_equal(c_ours > 0, c_theirs > 0) and ((c_ours > 0).sum(axis=1) == 2).all()
    assert c_ours[c_ours > 0].min() > 60  # 200 draws of two tied moves: about 100 each


def test_report_comparison_pairs_named_seeds_and_falls_back_to_welch(tmp_path, monkeypatch) -> None:
    from confront.experiments import tank_compare as tc
    from confront.train import league

    entries = ["1v1:SittingDuck", "4v4:td"]
    # the report lists its runs seed4 .. seed0; run seedK's share is 0.6 + 0.1 K
    rows = [{"entry": "1v1:SittingDuck", "sim": [1.0] * 5},
            {"entry": "4v4:td", "sim": [1.0 - 0.1 * k for k in range(5)]}]
    calls = []

    def shares(method, seed, entries, td_model, rounds, work):  # noqa: ANN001, ANN202
        calls.append((method, seed, td_model))
        return {"1v1:SittingDuck": 1.0, "4v4:td": 0.5 + 0.1 * seed}  # 0.1 below PPO tanks' share at every seed

    monkeypatch.setattr(tc, "method_shares", shares)
    monkeypatch.setattr(league, "td_team", lambda cfg, n: (None, Path(f"/c/td/t{cfg.train.seed}")))
    for runs, seeds, test in (([f"seed{4 - k}" for k in range(5)], [4, 3, 2, 1, 0], "paired"),
                              (["a", "b", "c", "d", "e"], [0, 1, 2, 3, 4], "welch")):
        calls.clear()
        (tmp_path / "results.json").write_text(json.dumps({"runs": runs, "rounds": 100, "play": "sampled",
                                                           "rows": rows}))
        res = tc.compare_report(tmp_path / "results.json", tmp_path / test, tmp_path / "work", [0, 1, 2, 3, 4])
        assert res["test"] == test and res["base_seeds"] == seeds and res["entries"] == entries
        assert calls[:3] == [(m, seeds[0], f"/c/td/t{seeds[0]}") for m in tc.METHODS] and len(calls) == 15
        for m in tc.METHODS:
            t = res["tests"][m]["4v4:td"]
            assert t["diff"] == pytest.approx(0.1)
            # paired by seed: +0.1 at each of 5 seeds, the smallest sign-flip p; unpaired: 0.1 against a 0.16 spread
            assert t["p"] == pytest.approx(1 / 32, abs=0.01) if test == "paired" else t["p"] > 0.1
        md = (tmp_path / test / "compare.md").read_text()
        assert "sampled" in md and ("Welch" in md) == (test == "welch")
    with pytest.raises(ValueError, match="evaluated 100 rounds"):
        tc.compare_report(tmp_path / "results.json", tmp_path / "x", tmp_path / "work", [0], rounds=30)


def test_report_curves_come_from_the_first_run_with_round_metrics(tmp_path, capsys) -> None:
    from confront.experiments.tank_report import _curves

    shipped, trained = tmp_path / "shipped", tmp_path / "trained"
    shipped.mkdir()  # a model folder as shipped: no metrics/rounds.csv
    (trained / "metrics").mkdir(parents=True)
    lines = ["opponent,decisions,wall_s,score_ours,score_theirs"]
    lines += [f"1v1:SpinBot,{100 * k},{0.5 * k},{k},{100 - k}" for k in range(1, 61)]
    (trained / "metrics" / "rounds.csv").write_text("\n".join(lines) + "\n")
    assert _curves([shipped], tmp_path / "a") == []
    assert "no learning curves" in capsys.readouterr().err
    (tmp_path / "b").mkdir()
    figs = _curves([shipped, trained], tmp_path / "b")
    assert [f.name for f in figs] == ["share_vs_decisions.png", "share_vs_wall_s.png"]
    assert all(f.stat().st_size > 1000 for f in figs)


def test_report_end_to_end_from_a_trained_run(tmp_path) -> None:
    """tank_report.report on a real (tiny) run: the simulator shares are evaluate_tanks' at battle seed 10000 and
    cached per play, the engine rows come from an earlier results.json of the same run only, and report.md and
    the curves are written; the command line refuses bad arguments with one line."""
    import subprocess
    import sys

    from confront.experiments.tank_report import report
    from confront.train.ppo_model import load_tank_model

    cfg = _cfg(tmp_path, "1v1:SittingDuck,1v1:SpinBot", **{"league.battles": "2", "train.rounds": "12"})
    run = tmp_path / "run"
    train_run(cfg, run, progress=False)
    earlier = tmp_path / "earlier.json"
    earlier.write_text(json.dumps({"runs": ["run"], "engine_seeds": 2, "unseen": [],
                                   "rows": [{"entry": "1v1:SpinBot", "engine": [0.81, 0.83]}]}))
    res = report([run], tmp_path / "out", rounds=4, engine=False, engine_seeds=1, engine_from=earlier,
                 play="sampled")
    want = evaluate_tanks(cfg, load_tank_model(run, cfg), 4, seed=10_000, explore=True)
    rows = {r["entry"]: r for r in res["rows"]}
    assert set(rows) == {"1v1:SittingDuck", "1v1:SpinBot"}
    for e, r in rows.items():
        assert r["sim"] == [want[e]["share"]]
    assert rows["1v1:SpinBot"]["engine"] == [0.81, 0.83] and rows["1v1:SittingDuck"]["engine"] is None
    assert res["engine_seeds"] == 2 and res["trained"][0]["rounds"] >= 12
    assert json.loads((run / "eval" / "sampled-4.json").read_text()) == {e: r["sim"][0] for e, r in rows.items()}
    md = (tmp_path / "out" / "report.md").read_text()
    assert "| 1v1:SpinBot |" in md and "0.810 / 0.830" in md
    assert {p.name for p in (tmp_path / "out").glob("share_vs_*.png")} == {"share_vs_decisions.png",
                                                                           "share_vs_wall_s.png"}
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"runs": ["elsewhere"], "engine_seeds": 1, "rows": []}))
    with pytest.raises(ValueError, match="is of run elsewhere, not run"):
        report([run], tmp_path / "out2", rounds=4, engine=False, engine_seeds=1, engine_from=other)
    cli = [sys.executable, "-m", "confront.experiments.tank_report", str(run), "--out", str(tmp_path / "o3")]
    bad = subprocess.run([*cli, "--engine", "--engine-from", str(earlier)], capture_output=True, text=True)
    assert bad.returncode == 2 and "--engine plays the battles, --engine-from reads them" in bad.stderr
    bad = subprocess.run([*cli, "--rounds", "0"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--rounds and --engine-seeds must be at least 1" in bad.stderr
    bad = subprocess.run([sys.executable, "-m", "confront.experiments.tank_report", str(tmp_path), "--out",
                          str(tmp_path / "o4")], capture_output=True, text=True)
    assert bad.returncode == 2 and "is not a trained run folder" in bad.stderr


def test_report_rows_from_an_earlier_report_of_the_same_training(tmp_path, monkeypatch, capsys) -> None:
    """--results-from: an earlier results.json is the run's when the name or the training summary matches; its
    play must be the report's; the rumble options refuse bad input with one line (exit 2)."""
    from confront.experiments.tank_report import earlier_results, main

    run = tmp_path / "run"
    run.mkdir()
    (run / "summary.json").write_text(json.dumps({"rounds": 120, "decisions": 4000, "wall_time_s": 3.0}))
    earlier = tmp_path / "results.json"
    base = {"runs": ["seed0"], "play": "sampled", "rows": [], "trained": [{"rounds": 120, "decisions": 4000}]}
    earlier.write_text(json.dumps(base))
    assert earlier_results(earlier, run, "sampled") == base  # renamed, the same training
    with pytest.raises(ValueError, match="of the sampled policy: give --play sampled"):
        earlier_results(earlier, run, "greedy")
    earlier.write_text(json.dumps({**base, "trained": [{"rounds": 120, "decisions": 4001}]}))
    with pytest.raises(ValueError, match="is of run seed0, not run"):
        earlier_results(earlier, run, "sampled")
    (run / "config.toml").write_text("")
    (run / "model").mkdir()
    (run / "model" / "model.json").write_text("{}")
    for extra, words in ((["--rumble", str(tmp_path / "nowhere")], "no such folder"),
                         (["--rumble", str(tmp_path), "--rumble-seeds", "0"], "must be at least 1"),
                         (["--results-from", str(earlier), "--engine"], "give one run, without --engine")):
        monkeypatch.setattr("sys.argv", ["tank_report", str(run), "--out", str(tmp_path / "o"), *extra])
        with pytest.raises(SystemExit) as exc:
            main()
        assert exc.value.code == 2 and words in capsys.readouterr().err


def test_pfsp_probabilities_hand_computed() -> None:
    from confront.train.league import pfsp_playing

    # shares 1, 0.5, 0: w = 0, 0.25, 1 (power 2); p = clip(0.5 * 3 * w / 1.25, 0.1, 1) = 0.1, 0.3, 1
    rng = np.random.default_rng(0)
    draws = np.array([pfsp_playing(np.array([1.0, 0.5, 0.0]), rng, 0.5, 0.1, 2.0) for _ in range(20000)])
    np.testing.assert_allclose(draws.mean(axis=0), [0.1, 0.3, 1.0], atol=0.01)
    # power 0: uniform, each with the fraction's chance, plus a third of P(none) = 1/8 (one is drawn then)
    uniform = np.array([pfsp_playing(np.array([1.0, 0.5, 0.0]), rng, 0.5, 0.1, 0.0) for _ in range(20000)])
    np.testing.assert_allclose(uniform.mean(axis=0), [0.5 + 0.125 / 3] * 3, atol=0.015)
    # all won: uniform at the fraction, and never none
    won = np.array([pfsp_playing(np.ones(4), rng, 0.5, 0.1, 2.0) for _ in range(4000)])
    assert won.sum(axis=1).min() == 1 and won.mean() == pytest.approx(0.5 + 0.0625 / 4, abs=0.02)


def test_recent_shares_over_each_entrys_last_rounds() -> None:
    from confront.train.league import recent_shares

    rows = [{"opponent": "a", "share": s} for s in (0.0, 1.0, 0.2, 0.4)] + [{"opponent": "b", "share": 0.9}]
    np.testing.assert_allclose(recent_shares(rows, ["a", "b", "c"], 2), [0.3, 0.9, 0.5])
    np.testing.assert_allclose(recent_shares(rows, ["a"], 10), [0.4])


def test_prioritised_league_plays_more_of_what_it_loses(tmp_path) -> None:
    """With prioritise, the entry the untrained policy loses to (4v4 Walls) gets more rounds than the sitting duck
    it beats from the start; without, the duck's short rounds are the most."""
    def rounds_of(prioritise: str) -> dict[str, int]:
        cfg = _cfg(tmp_path, "1v1:SittingDuck,4v4:Walls", **{"league.battles": "4", "train.rounds": "400",
                                                             "league.prioritise": prioritise,
                                                             "league.play_floor": "0.1"})
        trainer = TankTrainer(cfg)
        while trainer.rounds_done < 400:
            trainer.update()
        return {e: sum(r["opponent"] == e for r in trainer.rows) for e in ("1v1:SittingDuck", "4v4:Walls")}

    plain, pfsp = rounds_of("false"), rounds_of("true")
    assert plain["1v1:SittingDuck"] > plain["4v4:Walls"]
    assert pfsp["4v4:Walls"] / pfsp["1v1:SittingDuck"] > 2 * plain["4v4:Walls"] / plain["1v1:SittingDuck"]
