"""The local solver: its checkpoint round-trips, bad checkpoints are one-line errors (also
through the CLI), and its tours at K = 200 are feasible and priced by the evaluator."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.am import AttentionPolicy  # noqa: E402
from gtsp_bench.solvers.learned.checkpoint import load_policy, save_policy  # noqa: E402
from gtsp_bench.solvers.learned.local import LocalPolicy  # noqa: E402
from gtsp_bench.solvers.learned.local_solver import Local  # noqa: E402

from gtsp_bench.cli import main  # noqa: E402
from gtsp_bench.data.parse import format_json_instance  # noqa: E402
from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import instance_set  # noqa: E402
from gtsp_bench.registry import get_solver, run_solver  # noqa: E402


def _tiny(tmp_path, seed: int = 0):
    torch.manual_seed(seed)
    model = LocalPolicy(dim=16, n_heads=2, n_layers=1, ff=32, k=6)
    path = tmp_path / "local.pt"
    save_policy(model, path)
    return model, path


def test_checkpoint_round_trip(tmp_path):
    """A saved local policy reloads with the same weights and the same tours."""
    model, path = _tiny(tmp_path)
    loaded = load_policy(path, "local")
    assert loaded.config == model.config
    insts = instance_set(3, 12, 4_343, 6)
    solver = Local(checkpoint=str(path), starts=2)
    sols = solver.solve_batch(insts, [0.3] * 3)
    again = Local(checkpoint=str(path), starts=2).solve_batch(insts, [0.3] * 3)
    assert [s.order for s in sols] == [s.order for s in again]
    for a, b in zip(model.state_dict().values(), loaded.state_dict().values(), strict=True):
        assert torch.equal(a, b)


def test_wrong_kind_or_shape_is_one_line_error(tmp_path, capsys):
    """An am checkpoint or one whose weights do not fit its config: one line naming the file;
    through the CLI ``gtsp-bench: error: FILE: problem`` and exit code 2."""
    am = tmp_path / "am.pt"
    save_policy(AttentionPolicy(dim=16, n_heads=2, n_layers=1, ff=16), am)
    other = LocalPolicy(dim=16, n_heads=2, n_layers=1, ff=32, k=6)
    other.config = {**other.config, "dim": 24}
    shape = tmp_path / "shape.pt"
    save_policy(other, shape)
    inst = instance_set(1, 5, 4_343, 6)[0]
    for bad, message in ((am, "holds a 'am' model, not 'local'"),
                         (shape, "weights do not fit the model config")):
        with pytest.raises(InputError, match=message) as err:
            Local(checkpoint=str(bad)).solve(inst, 0.3)
        assert "\n" not in str(err.value) and str(bad) in str(err.value)
    path = tmp_path / "inst.json"
    path.write_text(format_json_instance(inst))
    assert main(["solve", str(path), "-s", "local", "-p", f"checkpoint={am}"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"gtsp-bench: error: {path}: {am}: checkpoint holds") and "\n" not in err


def test_feasible_at_k200_and_priced_by_the_evaluator(tmp_path):
    """Through the registry at K = 200: a feasible tour whose objective is the evaluator's (run_solver
    refuses a claimed objective the evaluator does not confirm)."""
    _, path = _tiny(tmp_path)
    inst = instance_set(1, 200, 4_343, 6, area=3_000.0)[0]
    result = run_solver(get_solver("local", checkpoint=str(path), starts=2), inst, 0.6)
    assert result.status == "feasible"
    assert sorted(result.order) == list(range(200))


def test_options_are_checked():
    with pytest.raises(InputError, match="starts"):
        Local(starts=0)
    with pytest.raises(InputError, match="heads"):
        Local(heads="best")
