"""Training recipes: one source per name, shared by the Python API and ``gtsp-bench train``."""

from __future__ import annotations

import dataclasses
import json
import shlex

import pytest

pytest.importorskip("torch")

from gtsp_bench.solvers.learned.checkpoint import CHECKPOINT_DIR
from gtsp_bench.solvers.learned.policies import POLICIES, build_policy
from gtsp_bench.solvers.learned.recipes import DEFAULT_RECIPE, RECIPES, TrainConfig, get_recipe
from gtsp_bench.solvers.learned.train import policy_config

from gtsp_bench.cli import build_parser, train_config
from gtsp_bench.errors import InputError


def _cli(argv: list[str]) -> TrainConfig:
    """The config ``gtsp-bench train ARGV -o x.pt`` would train."""
    return train_config(build_parser().parse_args(["train", *argv, "-o", "x.pt"]))


def test_recipes_are_named_by_their_key_and_include_the_shipped_and_the_paper():
    """Every recipe is a valid TrainConfig named by its key; drl, drl-paper and am exist and the
    CLI's default is one of them."""
    assert {"drl", "drl-paper", "am"} <= set(RECIPES) and DEFAULT_RECIPE in RECIPES
    for name, cfg in RECIPES.items():
        assert isinstance(cfg, TrainConfig) and cfg.recipe == name and cfg.model in POLICIES
    paper = RECIPES["drl-paper"]  # section VI: K = 4, 40,000 steps of 256, lr 1e-4, the critic
    assert (paper.clusters, paper.steps, paper.batch, paper.lr) == (4, 40_000, 256, 1e-4)
    assert paper.baseline == "critic" and paper.heads == "paper" and not paper.direction
    assert paper.model_options == {"glimpse": "all"} and paper.max_time is None


@pytest.mark.parametrize("name", sorted(RECIPES))
def test_python_api_and_cli_build_the_identical_config(name):
    """get_recipe(NAME) and `gtsp-bench train --model NAME` are the same config, with no switch
    and with switches that override fields."""
    assert _cli(["--model", name]) == get_recipe(name)
    switches = ["--seed", "5", "--batch", "32", "--steps", "100", "--omega", "0.4", "--max-time",
                "none", "--keep", "last", "--heads", "optimal", "--val-every", "20", "--threads", "2"]
    expect = get_recipe(name, seed=5, batch=32, steps=100, omega=0.4, max_time=None, keep="last",
                        heads="optimal", val_every=20, log_every=10, threads=2)
    assert _cli(["--model", name, *switches]) == expect


def test_cli_default_is_the_default_recipe():
    """Without --model, `gtsp-bench train` trains DEFAULT_RECIPE."""
    assert _cli([]) == get_recipe(DEFAULT_RECIPE)


def test_drl_switches_override_the_model_options():
    """--glimpse, --local, --energy and --direction set the one field they name; --no-local also
    drops the energy features (they extend the local term)."""
    assert _cli(["--model", "drl", "--no-energy"]).model_options == {"glimpse": "unvisited", "local": True}
    plain = _cli(["--model", "drl", "--glimpse", "all", "--no-local", "--no-direction"])
    assert plain == dataclasses.replace(get_recipe("drl-paper"), recipe="drl", max_time=2280.0)
    local = _cli(["--model", "drl-paper", "--local", "--direction"])
    assert local.model_options == {"glimpse": "all", "local": True} and local.direction
    with pytest.raises(InputError, match="--energy adds features to the --local term: add --local"):
        _cli(["--model", "drl-paper", "--energy"])


@pytest.mark.parametrize("cfg", [
    *RECIPES.values(),
    get_recipe("drl", max_time=None, omega=0.25, val_every=20, log_every=10, lr=3e-5),
    get_recipe("drl", model_options={"glimpse": "unvisited", "local": True}, direction=False),
    get_recipe("drl-paper", model_options={"glimpse": "unvisited"}, seed=9, max_time=60.5),
    get_recipe("am", batch=128, keep="best", max_time=None, heads="paper"),
], ids=lambda c: c.recipe)
def test_recorded_command_rebuilds_the_config(cfg):
    """The command line recorded beside a policy file, run again, trains the same config."""
    argv = shlex.split(cfg.command("out.pt"))
    assert argv[:3] == ["gtsp-bench", "train", "--model"] and argv[3] == cfg.recipe
    assert train_config(build_parser().parse_args(argv[1:])) == cfg


@pytest.mark.parametrize("name", ["drl", "am"])
def test_shipped_recipes_are_what_the_shipped_models_were_trained_with(name):
    """The JSON beside each shipped model: its command, run today, is the recipe; its recorded
    settings and its policy's config are the recipe's."""
    meta = json.loads((CHECKPOINT_DIR / f"{name}.json").read_text())
    recipe = RECIPES[name]
    argv = shlex.split(meta["command"])
    assert train_config(build_parser().parse_args(argv[1:])) == recipe
    recorded = dict(meta["train"])
    recorded["heads"] = recorded["heads"] or meta["validation"]["heads"]  # null: the model's default
    for key, value in recorded.items():
        assert getattr(recipe, key) == value, key
    assert build_policy(policy_config(recipe)).config == meta["config"]


def test_bad_names_settings_and_values_are_input_errors():
    """An unknown recipe lists the valid ones; unknown settings and bad values are refused; a
    config cannot be built without every setting (no second set of defaults)."""
    with pytest.raises(InputError, match="recipe must be one of 'drl', 'drl-paper', 'am'"):
        get_recipe("pointer")
    with pytest.raises(InputError, match="unknown training setting"):
        get_recipe("drl", glimpse="all")
    with pytest.raises(InputError, match="batch must be an integer >= 1"):
        get_recipe("am", batch=0)
    with pytest.raises(InputError, match="baseline of the am policy must be one of 'pomo'"):
        get_recipe("am", baseline="critic")
    with pytest.raises(InputError, match="baseline of the drl policy must be one of 'critic'"):
        get_recipe("drl", baseline="pomo")
    with pytest.raises(InputError, match="model must be one of 'drl', 'am'"):
        get_recipe("drl", model="lstm")
    with pytest.raises(InputError, match="keep must be one of 'best', 'last'"):
        get_recipe("drl", keep="first")
    with pytest.raises(InputError, match="val_every must be a multiple of log_every"):
        get_recipe("drl", val_every=75)
    with pytest.raises(InputError, match="model_options must be a mapping"):
        get_recipe("drl", model_options="local")
    with pytest.raises(TypeError):
        TrainConfig(model="drl")  # type: ignore[call-arg]
    with pytest.raises(InputError, match="recipe must be one of"):
        _cli(["--model", "paper"])


def test_configs_do_not_share_model_options_with_the_recipes():
    """Changing a config's options dict leaves the recipe it came from alone."""
    cfg = get_recipe("drl")
    cfg.model_options["dim"] = 8
    assert "dim" not in RECIPES["drl"].model_options and "dim" not in get_recipe("drl").model_options


def test_cli_help_lists_every_recipe(capsys):
    """--model takes a recipe name (not checked by argparse, to keep torch out of start-up): the
    help names every recipe."""
    with pytest.raises(SystemExit):
        build_parser().parse_args(["train", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for name in RECIPES:
        assert name in text
