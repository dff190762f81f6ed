"""Imitation training of the local policy: states from known tours, a loss that training moves,
a tiny end-to-end run with its files, and one-line errors for bad settings."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.checkpoint import load_policy  # noqa: E402
from gtsp_bench.solvers.learned.env import env_from_instances  # noqa: E402
from gtsp_bench.solvers.learned.imitation import (  # noqa: E402
    LOG_COLUMNS,
    get_recipe,
    imitation_loss,
    main,
    random_maps,
    train,
    walk_states,
)
from gtsp_bench.solvers.learned.local import LocalPolicy  # noqa: E402

from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import instance_set  # noqa: E402


def _states(k: int = 8, n: int = 4, view: int = 5):
    insts = instance_set(n, k, 4_545, 6)
    env = env_from_instances(insts, [0.3] * n)
    orders = torch.stack([torch.randperm(k, generator=torch.Generator().manual_seed(i)) for i in range(n)])
    return walk_states(env, orders, view), orders


def test_walk_states_point_at_the_tour():
    """Every state's target is the tour's next cluster; the last step (one candidate) is left out."""
    (samples, share), _ = _states()
    assert 0 < share <= 1
    assert len(samples) == round(share * 4 * 7)
    (whole, all_in), _ = _states(view=8)  # the view holds every cluster: every step is a state
    assert all_in == 1.0 and len(whole) == 4 * 7
    assert samples.mask[torch.arange(len(samples)), samples.target].all()
    # the first state of each tour: all 8 clusters left, 5 in view
    assert samples.mask[:4].sum(1).tolist() == [5] * 4


def test_training_a_few_steps_changes_the_loss():
    """A tiny model's loss on fixed states falls after a few Adam steps."""
    torch.manual_seed(0)
    (samples, _), _ = _states()
    model = LocalPolicy(dim=16, n_heads=2, n_layers=1, ff=32, k=5)
    maps = random_maps(len(samples), torch.Generator().manual_seed(0))
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    first = float(imitation_loss(model, samples, maps)[0].detach())
    for _ in range(15):
        loss, _ = imitation_loss(model, samples, maps)
        opt.zero_grad()
        loss.backward()
        opt.step()
    assert float(imitation_loss(model, samples, maps)[0].detach()) < first - 0.05


def test_tiny_run_writes_policy_log_and_meta(tmp_path):
    """Labels by lns, states, a few steps: the policy loads, the log and the JSON say what ran,
    and a second run reuses the cached labels."""
    cfg = get_recipe("local-small", mix=((5, 3, 1000.0),), max_time=1.0, steps=4, val=(5, 2, 1000.0),
                     val_every=2, log_every=2, batch=8, model_options={"dim": 16, "n_heads": 2,
                                                                        "n_layers": 1, "ff": 32, "k": 4})
    out = tmp_path / "p.pt"
    meta = train(cfg, out, progress=False)
    assert load_policy(out, "local").config["dim"] == 16
    assert meta["steps_trained"] == 4 and [list(m) for m in meta["train"]["mix"]] == [[5, 3, 1000.0]]
    assert json.loads((tmp_path / "p.json").read_text())["command"].startswith(
        "python -m gtsp_bench.solvers.learned.imitation --recipe local-small")
    lines = (tmp_path / "p.imitation.csv").read_text().splitlines()
    assert lines[0] == ",".join(LOG_COLUMNS) and len(lines) == 4
    assert (tmp_path / "p.labels.npz").is_file()
    assert train(cfg, out, progress=False)["label_wall_s"] == 0.0


def test_tiled_entries_label_at_omega_zero(tmp_path):
    """A tiled mix entry: tiled instances at omega 0, their own cache key, a tiled validation
    whose gap is the distance's (hover energies left out), all alongside a squares entry."""
    cfg = get_recipe("local-small", mix=((5, 2, 1000.0), (6, 3, 1000.0, "tiled")), max_time=1.0,
                     steps=2, val=(6, 2, 1000.0, "tiled"), val_every=2, log_every=2, batch=8,
                     model_options={"dim": 16, "n_heads": 2, "n_layers": 1, "ff": 32, "k": 4})
    meta = train(cfg, tmp_path / "p.pt", progress=False)
    assert set(meta["next_in_view"]) == {"5", "6t"}
    assert meta["validation"]["tiled"] and meta["validation"]["omega"] == [0.0]
    with np.load(tmp_path / "p.labels.npz") as f:
        assert sorted(f.files) == ["K5_n2_a1000_s71000_w0.9_N20", "K6_n3_tiled_s71000",
                                   "val_K6_n2_tiled"]
    # a one-start greedy tour is never below lns's, distance alone
    assert meta["val_gap_pct"] >= -1e-9


def test_several_validation_sets_and_averaged_weights(tmp_path):
    """Validation over two sets (their references cached beside the labels, the gap the mean of
    the two) and an exponential average of the weights, which is what the file holds."""
    from gtsp_bench.solvers.learned.imitation import greedy_gap
    from gtsp_bench.solvers.learned.labels import validation_set

    opts = {"dim": 16, "n_heads": 2, "n_layers": 1, "ff": 32, "k": 4}
    cfg = get_recipe("local-small", mix=((5, 3, 1000.0),), max_time=60.0, steps=6,
                     val=((5, 2, 1000.0), (7, 2, 1000.0)), val_every=6, log_every=2, batch=8,
                     ema=0.5, model_options=opts)
    assert cfg.val == ((5, 2, 1000.0), (7, 2, 1000.0))
    assert get_recipe("local-small", val=(5, 2, 1000.0)).val == ((5, 2, 1000.0),)
    assert get_recipe("local-small", val=[[5, 2, 1000.0]]).val == ((5, 2, 1000.0),)  # as in JSON
    meta = train(cfg, tmp_path / "p.pt", progress=False)
    assert meta["validation"]["sets"] == [[5, 2, 1000.0], [7, 2, 1000.0]]
    with np.load(tmp_path / "p.labels.npz") as f:
        assert sorted(f.files) == ["K5_n3_a1000_s71000_w0.9_N20", "val_K5_n2_a1000_N20",
                                   "val_K7_n2_a1000_N20"]
        refs = {k: f[f"val_K{k}_n2_a1000_N20"] for k in (5, 7)}
    policy = load_policy(tmp_path / "p.pt", "local")
    gaps = []
    for k in (5, 7):
        insts, omegas = validation_set((k, 2, 1000.0), 20)
        assert omegas == [0.3, 0.6]
        gaps.append(greedy_gap(policy, env_from_instances(insts, omegas), torch.from_numpy(refs[k])))
    assert meta["val_gap_pct"] == pytest.approx(np.mean(gaps))
    assert min(gaps) >= -1e-9  # lns's tours are optimal at this size: greedy is never below


def test_averaged_weights_are_not_the_last_ones(tmp_path, monkeypatch):
    """With ``ema`` the file holds the running average, not the weights of the last step."""
    from gtsp_bench.solvers.learned import imitation

    opts = {"dim": 16, "n_heads": 2, "n_layers": 1, "ff": 32, "k": 4}
    saved: list[dict[str, torch.Tensor]] = []
    monkeypatch.setattr(imitation, "save_policy", lambda m, p: saved.append(
        {k: v.clone() for k, v in m.state_dict().items()}))
    kept = {}
    for ema in (0.0, 0.9):
        cfg = get_recipe("local-small", mix=((5, 3, 1000.0),), max_time=60.0, steps=4,
                         val=(5, 2, 1000.0), val_every=100, log_every=100, batch=8, ema=ema,
                         model_options=opts, lr=0.05)
        train(cfg, tmp_path / "p.pt", progress=False)
        kept[ema] = saved[-1]
    # the same seed and batches: the plain run's last weights differ from their average
    assert any(not torch.equal(kept[0.0][k], kept[0.9][k]) for k in kept[0.0])


def test_bad_settings(capsys):
    with pytest.raises(InputError, match="ema"):
        get_recipe("local", ema=1.0)
    with pytest.raises(InputError, match="validation"):
        get_recipe("local", val=())
    with pytest.raises(InputError, match="tiled"):
        get_recipe("local", mix=((10, 5, 1000.0, "rings"),))
    with pytest.raises(InputError, match="test set's seed"):
        get_recipe("local", label_seed=5_000)
    with pytest.raises(InputError, match="recipe"):
        get_recipe("nope")
    assert main(["--recipe", "nope", "-o", "x.pt"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gtsp-bench: error: ") and "\n" not in err


def test_states_walked_in_workers_are_the_same():
    """States walked in two forked processes equal those of one process."""
    from gtsp_bench.solvers.learned.imitation import build_samples
    from gtsp_bench.solvers.learned.labels import label_set, solve_labels

    insts, omegas = label_set(6, 4, 1000.0, 71_000, 6, 0.9)
    one, _ = solve_labels(insts, omegas)
    cfg = get_recipe("local-small", mix=((6, 4, 1000.0),), nodes=6)
    a, _ = build_samples(cfg, {(6, 4, 1000.0): one}, 4)
    b, _ = build_samples(cfg, {(6, 4, 1000.0): one}, 4,
                         pool=__import__("multiprocessing").get_context("fork").Pool(2))
    assert torch.equal(a.cand_vec, b.cand_vec) and torch.equal(a.target, b.target)


def test_bad_device_or_workers_is_one_line(capsys):
    for args in (["--device", "nope"], ["--workers", "0"]):
        assert main(["--recipe", "local-small", *args, "-o", "x.pt"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("gtsp-bench: error: ") and "\n" not in err


def test_gpu_recipes_record_their_command():
    """The GPU recipes' command line names the device and the workers it ran with."""
    cfg = get_recipe("local-gpu-l3", seed=2)
    assert cfg.command("p.pt", "cuda", 15) == (
        "python -m gtsp_bench.solvers.learned.imitation --recipe local-gpu-l3 --max-time 165 "
        "--seed 2 --device cuda --workers 15 -o p.pt")
    assert cfg.model_options == {"dim": 96, "n_layers": 3, "ff": 192}


def _tuples(x):
    return tuple(_tuples(v) for v in x) if isinstance(x, list) else x


@pytest.mark.parametrize("name", ["local-l4", "local-l4-tiled"])
def test_shipped_gpu_policies_were_trained_by_their_recipe(name):
    """The JSON beside a shipped l4 policy: its recorded settings are its recipe's (with the
    seed and time of its command), and the file holds a policy of the recorded size."""
    import shlex

    from gtsp_bench.solvers.learned import CHECKPOINT_DIR
    from gtsp_bench.solvers.learned.imitation import ImitationConfig

    meta = json.loads((CHECKPOINT_DIR / f"{name}.json").read_text())
    argv = shlex.split(meta["command"])
    recipe = argv[argv.index("--recipe") + 1]
    cfg = get_recipe(recipe, seed=int(argv[argv.index("--seed") + 1]),
                     max_time=float(argv[argv.index("--max-time") + 1]))
    recorded = {k: _tuples(v) for k, v in meta["train"].items()}
    recorded["model_options"] = meta["train"]["model_options"]
    assert ImitationConfig(**recorded) == cfg
    assert LocalPolicy(**cfg.model_options).config == meta["config"]
    assert load_policy(CHECKPOINT_DIR / f"{name}.pt", "local").config == meta["config"]
