"""The learned solvers (drl, drl-sample, am): the harness accepts their tours, the options,
the shipped checkpoints, and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.am import AttentionPolicy  # noqa: E402
from gtsp_bench.solvers.learned.checkpoint import CHECKPOINT_DIR, save_policy  # noqa: E402
from gtsp_bench.solvers.learned.drl import PointerPolicy  # noqa: E402

from gtsp_bench.cli import main  # noqa: E402
from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import generate_instance  # noqa: E402
from gtsp_bench.instance import Instance  # noqa: E402
from gtsp_bench.registry import get_solver, run_solver  # noqa: E402
from tests.tiny_cases import not_below  # noqa: E402


def _tiny_am() -> AttentionPolicy:
    torch.manual_seed(2)
    return AttentionPolicy(dim=16, n_heads=2, n_layers=1, ff=32)


@pytest.fixture(scope="module")
def tiny_ckpt(tmp_path_factory):
    """An untrained tiny drl policy file for N = 5."""
    torch.manual_seed(1)
    path = tmp_path_factory.mktemp("drl") / "tiny.pt"
    save_policy(PointerPolicy(n_nodes=5, dim=16), path)
    return path


def test_drl_solvers_feasible_and_sampling_not_worse(tiny_ckpt):
    """drl and drl-sample pass the harness; sampling keeps the greedy tour, so it is never worse."""
    inst = generate_instance(5, 5, seed=2)
    for heads in ("paper", "optimal"):
        greedy = run_solver(get_solver("drl", checkpoint=str(tiny_ckpt), heads=heads), inst, 0.3)
        sample = run_solver(get_solver("drl-sample", checkpoint=str(tiny_ckpt), heads=heads,
                                       samples=16), inst, 0.3, seed=4)
        again = run_solver(get_solver("drl-sample", checkpoint=str(tiny_ckpt), heads=heads,
                                      samples=16), inst, 0.3, seed=4)
        assert sample.objective <= greedy.objective + 1e-9
        assert again.objective == sample.objective and again.order == sample.order
    paper = run_solver(get_solver("drl", checkpoint=str(tiny_ckpt)), inst, 0.3)
    optimal = run_solver(get_solver("drl", checkpoint=str(tiny_ckpt), heads="optimal"), inst, 0.3)
    assert paper.order == optimal.order and optimal.objective <= paper.objective + 1e-9


def test_reverse_keeps_the_better_direction():
    """reverse=true: with the paper's heads the tour is the decoded one or its reverse, whichever
    the evaluator prices lower (never worse; better on some of 40 instances with the shipped
    model); with optimal heads both directions cost the same, so the objective is unchanged."""
    from gtsp_bench.generator import instance_set

    insts = instance_set(40, 6, 77)
    plain = get_solver("drl").solve_batch(insts, [0.4] * 40)
    rev = get_solver("drl", reverse=True).solve_batch(insts, [0.4] * 40)
    better = 0
    for inst, a, b in zip(insts, plain, rev, strict=True):
        assert b.order in (a.order, a.order[::-1])
        back = run_solver(get_solver("drl", reverse=True), inst, 0.4)
        assert back.objective == pytest.approx(b.objective, rel=1e-12)
        assert b.objective <= a.objective + 1e-9
        better += b.objective < a.objective - 1e-9
    assert better >= 1
    opt = get_solver("drl", heads="optimal").solve_batch(insts, [0.4] * 40)
    opt_rev = get_solver("drl", heads="optimal", reverse=True).solve_batch(insts, [0.4] * 40)
    assert [s.objective for s in opt] == pytest.approx([s.objective for s in opt_rev], rel=1e-9)
    with pytest.raises(InputError, match="reverse must be true or false"):
        get_solver("drl", reverse="yes")


def test_bad_options_and_wrong_cluster_size(tiny_ckpt):
    """Bad options and a cluster size the model was not built for raise InputError."""
    with pytest.raises(InputError, match="heads must be one of"):
        get_solver("drl", heads="best")
    with pytest.raises(InputError, match="samples must be an integer"):
        get_solver("drl-sample", samples=-1)
    with pytest.raises(InputError, match="trained on clusters of 5 nodes"):
        run_solver(get_solver("drl", checkpoint=str(tiny_ckpt)), generate_instance(3, 6, seed=0), 0.5)


def test_shipped_checkpoint_solves_from_the_cli(tmp_path, capsys):
    """The committed drl model (and its JSON record) solves a fresh instance via the CLI."""
    meta = json.loads((CHECKPOINT_DIR / "drl.json").read_text())
    assert meta["model"] == "drl" and meta["config"]["n_nodes"] == 20 and meta["steps"] > 0
    inst = tmp_path / "k6.json"
    assert main(["generate", "-k", "6", "--seed", "3", "-o", str(inst)]) == 0
    capsys.readouterr()
    assert main(["solve", str(inst), "-s", "drl", "-w", "0.3", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert sorted(data["order"]) == list(range(6)) and data["solver"] == "drl"


def test_cli_checkpoint_param_error_is_one_line(tmp_path, capsys):
    """solve -p checkpoint=BAD exits 2 with one line naming the file."""
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"\x00garbage")
    inst = tmp_path / "k3.json"
    assert main(["generate", "-k", "3", "-o", str(inst)]) == 0
    capsys.readouterr()
    assert main(["solve", str(inst), "-s", "drl", "-p", f"checkpoint={bad}"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and str(bad) in err


def test_am_solver_takes_any_cluster_size(tmp_path):
    """The am solver solves clusters of unequal size (padded) and the harness accepts the tour."""
    path = tmp_path / "am.pt"
    save_policy(_tiny_am(), path)
    clusters = tuple(np.random.default_rng(i).uniform(100 * i, 100 * i + 90, (3 + i, 2))
                     for i in range(5))
    inst = Instance("uneven", clusters, depot=np.array([500.0, 0.0]))
    for heads in ("optimal", "paper"):
        result = run_solver(get_solver("am", checkpoint=str(path), heads=heads), inst, 0.6)
        assert sorted(result.order) == list(range(5))
        assert all(h < 3 + c for c, h in enumerate(result.heads))
        both = run_solver(get_solver("am", checkpoint=str(path), heads=heads, augment=True), inst, 0.6)
        assert both.objective <= result.objective + 1e-9  # the plain tours are among the candidates


def test_shipped_am_checkpoint_solves():
    """The committed am model (shipped: its loss fails the test) loads and solves K = 7, N = 20,
    never below the DP's optimum."""
    assert (CHECKPOINT_DIR / "am.pt").is_file()
    inst = generate_instance(7, seed=5)
    result = run_solver("am", inst, 0.6)
    assert sorted(result.order) == list(range(7))
    assert not_below(result.objective, run_solver("dp", inst, 0.6).objective)


def test_drl_sample_reports_its_greedy_tour_first(tiny_ckpt):
    """drl-sample reports the greedy tour (drl's answer) before it samples, then the better
    sampled one: the same answer as a batch solve, and a trajectory that never rises."""
    found = False
    for seed in range(6):
        inst = generate_instance(6, 5, seed=seed)
        greedy = run_solver(get_solver("drl", checkpoint=str(tiny_ckpt)), inst, 0.3)
        solver = get_solver("drl-sample", checkpoint=str(tiny_ckpt), samples=16)
        r = run_solver(solver, inst, 0.3, seed=1)
        batch = solver.solve_batch([inst], [0.3], seed=1)[0]
        assert (r.order, r.heads) == (batch.order, batch.heads)
        objectives = [p.objective for p in r.trajectory]
        assert objectives[0] == pytest.approx(greedy.objective, rel=1e-9)
        assert objectives == sorted(objectives, reverse=True) and objectives[-1] == r.objective
        found |= len(objectives) == 2
    assert found  # on some instance sampling beat the greedy tour
