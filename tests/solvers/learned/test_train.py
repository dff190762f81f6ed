"""Training: a tiny model learns a little, logs the documented columns, and resumes after a kill."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time

import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.checkpoint import load_policy  # noqa: E402
from gtsp_bench.solvers.learned.recipes import TrainConfig, get_recipe  # noqa: E402
from gtsp_bench.solvers.learned.train import Trainer, output_paths, policy_config, train  # noqa: E402

from gtsp_bench.cli import main  # noqa: E402
from gtsp_bench.errors import InputError  # noqa: E402
from tests.conftest import REPO  # noqa: E402


def _cfg(model: str = "drl", steps: int = 6, **kw) -> TrainConfig:
    """A tiny run of the paper's plain drl recipe, or of the am recipe."""
    options = {"dim": 16} if model == "drl" else {"dim": 16, "n_heads": 2, "n_layers": 1, "ff": 32}
    recipe = "drl-paper" if model == "drl" else model
    settings = {"clusters": 3, "nodes": 4, "steps": steps, "batch": 16, "lr": 1e-3, "seed": 7,
                "val_every": 2, "val_size": 8, "log_every": 1, "max_time": None, "keep": "best",
                "model_options": options, **kw}
    return get_recipe(recipe, **settings)


def _rows(path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("model", ["drl", "am"])
def test_tiny_model_trains_and_writes_its_files(tmp_path, model):
    """A few steps change the weights and the loss; policy, JSON and CSV log are written."""
    trainer = Trainer(_cfg(model), tmp_path / "m.pt")
    before = {k: v.clone() for k, v in trainer.model.state_dict().items()}
    meta = trainer.run(progress=False)
    after = trainer.model.state_dict()
    assert any(not torch.equal(before[k], after[k]) for k in before)
    paths = output_paths(tmp_path / "m.pt")
    rows = _rows(paths["log"])
    with open(paths["log"]) as f:
        assert f.readline().startswith("step,loss,reward,val_energy,wall_s")
    assert [int(r["step"]) for r in rows] == list(range(7))
    losses = {float(r["loss"]) for r in rows[1:]}
    assert len(losses) > 1
    assert all(float(r["reward"]) < 0 for r in rows[1:])
    assert float(rows[0]["val_gap_pct"]) >= -1e-9  # greedy is never below the exact optimum
    assert meta["model"] == model and meta["steps_trained"] == 6 and meta["val_energy"] > 0
    assert meta["command"].startswith(f"gtsp-bench train --model {model}")
    assert load_policy(paths["policy"], model).config == trainer.model.config


def test_direction_term_moves_the_odds_toward_the_cheaper_direction(tmp_path):
    """The direction term is mean(|c - c_rev| softplus(-sign(c_rev - c) (lp - lp_rev))), lp the
    log-probability of a tour's first step; a gradient step on it alone raises the log-odds of
    the cheaper direction (weighted by the cost gap), and pairs that cost the same give it no
    gradient."""
    from gtsp_bench.solvers.learned.env import COST_SCALE, choose_heads, tour_cost

    trainer = Trainer(_cfg(direction=True), tmp_path / "p.pt")
    env = trainer.batch_env()
    order, _, first = trainer.model.decode_first(env, "sample",
                                                 generator=torch.Generator().manual_seed(0))
    rev = order.flip(-1)
    with torch.no_grad():
        c = (tour_cost(env, order, choose_heads(env, order, "paper")) / COST_SCALE).float()
        c_rev = (tour_cost(env, rev, choose_heads(env, rev, "paper")) / COST_SCALE).float()
    assert (c != c_rev).any()  # the paper's rule makes the two directions cost differently

    def log_odds() -> torch.Tensor:
        return (trainer.model.decode(env, forced=order[:, :1])[1]
                - trainer.model.decode(env, forced=rev[:, :1])[1])

    loss = trainer._direction_loss(env, order, c, first)
    expect = ((c - c_rev).abs() * torch.nn.functional.softplus(-(c_rev - c).sign() * log_odds()))
    torch.testing.assert_close(loss, expect.mean())
    with torch.no_grad():
        before = ((c_rev - c) * log_odds()).mean()
    trainer.model.zero_grad()
    loss.backward()
    with torch.no_grad():
        for p in trainer.model.parameters():
            if p.grad is not None:
                p -= 10.0 * p.grad
        assert ((c_rev - c) * log_odds()).mean() > before
    trainer.model.zero_grad()
    c_same = (tour_cost(env, rev, choose_heads(env, rev, "paper")) / COST_SCALE).float()
    first = trainer.model.decode_first(env, forced=order[:, :1])[2]
    trainer._direction_loss(env, order, c_same, first).backward()  # equal costs: no signal
    assert all(p.grad is None or not p.grad.any() for p in trainer.model.parameters())


def test_direction_recorded_and_drl_only(tmp_path):
    """--direction is in the JSON's command; the am model refuses it."""
    meta = train(_cfg(steps=2, direction=True), tmp_path / "r.pt", progress=False)
    assert "--direction" in meta["command"] and meta["train"]["direction"] is True
    with pytest.raises(InputError, match="drl model only"):
        _cfg("am", direction=True)


def test_resume_rewrites_a_log_that_lags_the_state(tmp_path):
    """Killed after the state was saved and before the log was (the state is written first): a
    resumed run, even one with nothing left to train, rewrites the log from the state's rows."""
    Trainer(_cfg(steps=4), tmp_path / "run.pt").run(progress=False)
    log = output_paths(tmp_path / "run.pt")["log"]
    full = log.read_text()
    log.write_text("".join(full.splitlines(keepends=True)[:-1]))  # the last row lost
    resumed = Trainer(_cfg(steps=4), tmp_path / "run.pt", resume=True)
    resumed.run(progress=False)
    assert log.read_text() == full and [int(r["step"]) for r in _rows(log)][-1] == 4


def test_resume_after_interruption_continues_from_saved_step(tmp_path, monkeypatch):
    """Interrupted at step 5 (state saved at 4), a resumed run ends where an uninterrupted one does."""
    ref = Trainer(_cfg(steps=8), tmp_path / "ref.pt")
    ref.run(progress=False)

    broken = Trainer(_cfg(steps=8), tmp_path / "run.pt")
    original = Trainer.train_step

    def crash(self):
        if self.step == 5:
            raise KeyboardInterrupt
        return original(self)

    monkeypatch.setattr(Trainer, "train_step", crash)
    with pytest.raises(KeyboardInterrupt):
        broken.run(progress=False)
    monkeypatch.setattr(Trainer, "train_step", original)
    resumed = Trainer(_cfg(steps=8), tmp_path / "run.pt", resume=True)
    assert resumed.step == 4
    resumed.run(progress=False)
    for key, value in ref.model.state_dict().items():
        torch.testing.assert_close(resumed.model.state_dict()[key], value)
    steps = [int(r["step"]) for r in _rows(output_paths(tmp_path / "run.pt")["log"])]
    assert steps == list(range(9))


def test_state_guards(tmp_path):
    """An existing state needs --resume, other settings cannot resume it, corrupt state is refused."""
    train(_cfg(steps=2), tmp_path / "m.pt", progress=False)
    with pytest.raises(InputError, match="add --resume"):
        Trainer(_cfg(steps=4), tmp_path / "m.pt")
    with pytest.raises(InputError, match="other settings"):
        Trainer(TrainConfig(**{**_cfg(steps=4).__dict__, "lr": 0.5}), tmp_path / "m.pt", resume=True)
    output_paths(tmp_path / "m.pt")["state"].write_bytes(b"junk")
    with pytest.raises(InputError, match="corrupt training state"):
        Trainer(_cfg(steps=4), tmp_path / "m.pt", resume=True)
    with pytest.raises(InputError, match="no training state"):
        Trainer(_cfg(steps=4), tmp_path / "other.pt", resume=True)


def test_cli_train_killed_then_resumed(tmp_path, capsys):
    """A real SIGKILL mid-run: --resume continues from the saved step and the log has no repeats."""
    out = tmp_path / "k.pt"
    argv = ["train", "--model", "drl", "-k", "3", "-n", "4", "--steps", "4000", "--batch", "8",
            "--val-every", "10", "--val-size", "8", "--seed", "3", "--no-progress", "-o", str(out)]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    code = f"import sys; from gtsp_bench.cli import main; sys.exit(main({argv!r}))"
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, stderr=subprocess.PIPE)
    state = output_paths(out)["state"]
    log = output_paths(out)["log"]
    deadline = time.monotonic() + 40
    while time.monotonic() < deadline and (not log.exists() or len(_rows(log)) < 3):
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert state.exists(), proc.stderr.read().decode()
    saved = int(_rows(log)[-1]["step"])
    assert saved >= 10
    code = main([*argv[:argv.index("--steps") + 1], str(saved + 10), *argv[argv.index("--steps") + 2:],
                 "--resume"])
    assert code == 0, capsys.readouterr().err
    steps = [int(r["step"]) for r in _rows(log)]
    assert steps == sorted(set(steps)) and steps[-1] == saved + 10
    meta = json.loads(output_paths(out)["meta"].read_text())
    assert meta["steps_trained"] == saved + 10
    # the CLI trains drl with the glimpse over unvisited elements, and the command says so
    assert "--glimpse unvisited" in meta["command"] and meta["config"]["glimpse"] == "unvisited"


@pytest.mark.parametrize(("args", "message"), [
    (["--steps", "0"], "steps must be an integer >= 1"),
    (["--clusters", "1"], "at least 2 clusters"),
    (["--omega", "1.5"], "omega must be in [0, 1]"),
    (["--lr", "-1"], "learning rate must be a number"),
    (["--model", "am", "--glimpse", "all"], "--glimpse is an option of the drl model only"),
    (["--model", "am", "--local"], "--local is an option of the drl model only"),
    (["--energy", "--no-local"], "--energy adds features to the --local term"),
    (["--model", "am", "--direction"], "--direction is an option of the drl model only"),
])
def test_cli_train_bad_settings_exit_2(tmp_path, capsys, args, message):
    """Bad training settings: exit 2 with one line, and no file written."""
    code = main(["train", *args, "--no-progress", "-o", str(tmp_path / "x.pt")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_cli_train_defaults_are_the_shipped_recipe_and_recorded(tmp_path, capsys):
    """drl's defaults (--local --energy --direction, damp = the training K) and their --no-
    forms: the policy file's config, the JSON record and its command carry them, spelled out."""
    base = ["train", "--clusters", "3", "--nodes", "4", "--steps", "2", "--batch", "8",
            "--val-every", "2", "--val-size", "8", "--no-progress"]
    out = tmp_path / "loc.pt"
    assert main([*base, "-o", str(out)]) == 0, capsys.readouterr().err
    meta = json.loads(output_paths(out)["meta"].read_text())
    assert meta["config"]["local"] is True and meta["config"]["energy"] is True
    assert meta["config"]["damp"] == 3  # the training K
    assert meta["train"]["direction"] is True
    assert "--glimpse unvisited --local --energy --direction" in meta["command"]
    assert load_policy(out, "drl").local is not None
    plain = tmp_path / "plain.pt"
    argv = [*base, "--glimpse", "all", "--no-local", "--no-direction", "-o", str(plain)]
    assert main(argv) == 0, capsys.readouterr().err
    meta = json.loads(output_paths(plain)["meta"].read_text())
    assert "local" not in meta["config"] and "glimpse" not in meta["config"]
    assert meta["train"]["direction"] is False
    assert "--glimpse all --no-local --no-direction" in meta["command"]
    assert load_policy(plain, "drl").local is None


def test_policy_config_fills_the_training_shape():
    """drl's policy gets n_nodes = N and, with the local term, damp = the training K unless the
    options give them; am's options pass through unchanged."""
    assert policy_config(get_recipe("drl", clusters=5, nodes=7)) == {
        "model": "drl", "glimpse": "unvisited", "local": True, "energy": True, "n_nodes": 7, "damp": 5}
    assert policy_config(get_recipe("drl-paper", nodes=7)) == {"model": "drl", "glimpse": "all", "n_nodes": 7}
    custom = get_recipe("drl", model_options={"local": True, "damp": 2, "n_nodes": 9})
    assert policy_config(custom) == {"model": "drl", "local": True, "damp": 2, "n_nodes": 9}
    assert policy_config(get_recipe("am", model_options={"dim": 16})) == {"model": "am", "dim": 16}


@pytest.mark.parametrize("model", ["drl", "am"])
def test_the_baseline_gets_its_own_optimiser(tmp_path, model):
    """drl (critic baseline): one Adam over the actor's parameters, one over the critic's, which
    together are every parameter once; am (POMO, nothing to learn): one Adam over everything."""
    trainer = Trainer(_cfg(model), tmp_path / "m.pt")
    groups = [[id(p) for g in opt.param_groups for p in g["params"]] for opt in trainer.optims]
    every = [id(p) for p in trainer.model.parameters()]
    assert sorted(i for group in groups for i in group) == sorted(every)
    if model == "drl":
        assert len(groups) == 2
        assert groups[1] == [id(p) for p in trainer.model.critic.parameters()]
    else:
        assert len(groups) == 1
