"""Policy files: a round trip keeps the outputs; bad files are one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.checkpoint import load_policy, save_policy  # noqa: E402
from gtsp_bench.solvers.learned.drl import PointerPolicy  # noqa: E402
from gtsp_bench.solvers.learned.env import make_env  # noqa: E402

from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import generate_batch  # noqa: E402


def test_checkpoint_round_trip_and_bad_files(tmp_path):
    """A saved policy reloads with identical outputs; corrupt or mismatched files: one-line errors."""
    torch.manual_seed(0)
    model = PointerPolicy(n_nodes=5, dim=16)
    path = tmp_path / "p.pt"
    save_policy(model, path)
    loaded = load_policy(path, "drl")
    env = make_env(generate_batch(np.random.default_rng(0), 4, 4, 5), 0.3)
    with torch.no_grad():
        assert torch.equal(model.decode(env)[1], loaded.decode(env)[1])
    corrupt = tmp_path / "corrupt.pt"
    corrupt.write_bytes(path.read_bytes()[:200])
    truncated = tmp_path / "text.pt"
    truncated.write_text("not a checkpoint")
    other = PointerPolicy(n_nodes=5, dim=16)
    other.config = {"model": "drl", "n_nodes": 5, "dim": 32}  # shape mismatch
    mismatched = tmp_path / "mismatched.pt"
    save_policy(other, mismatched)
    cases = [(corrupt, "not a readable checkpoint"), (truncated, "not a readable checkpoint"),
             (mismatched, "weights do not fit the model config"),
             (tmp_path / "missing.pt", "no such checkpoint file")]
    for bad, message in cases:
        with pytest.raises(InputError, match=message) as err:
            load_policy(bad, "drl")
        assert "\n" not in str(err.value) and str(bad) in str(err.value)
    with pytest.raises(InputError, match="holds a 'drl' model, not 'am'"):
        load_policy(path, "am")
