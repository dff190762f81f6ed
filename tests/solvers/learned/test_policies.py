"""The policy registry: names to classes, configs to policies, and no import cycles."""

from __future__ import annotations

import ast

import pytest

pytest.importorskip("torch")

from gtsp_bench.solvers.learned.am import AttentionPolicy
from gtsp_bench.solvers.learned.baselines import BASELINES
from gtsp_bench.solvers.learned.drl import PointerPolicy
from gtsp_bench.solvers.learned.local import LocalPolicy
from gtsp_bench.solvers.learned.policies import POLICIES, build_policy, get_policy

from gtsp_bench.errors import InputError
from tests.conftest import REPO

LEARNED = REPO / "solvers" / "learned"
PACKAGE = "gtsp_bench.solvers.learned"


def test_registry_names_each_policy_and_its_baselines():
    """drl is the pointer network, am the attention model, local the local-view policy; the
    REINFORCE-trained ones support registered baselines (local is trained by imitation: none),
    and each writes its own name as the config's model."""
    assert {"drl": PointerPolicy, "am": AttentionPolicy, "local": LocalPolicy} == POLICIES
    assert get_policy("am") is AttentionPolicy
    assert LocalPolicy.baselines == ()
    for name, cls in POLICIES.items():
        assert (bool(cls.baselines) != (name == "local")) and set(cls.baselines) <= set(BASELINES)
        small = {"n_nodes": 3, "dim": 8} if name == "drl" else {"dim": 8, "n_heads": 2, "ff": 16}
        assert build_policy({"model": name, **small}).config["model"] == name


def test_build_policy_round_trips_a_config():
    """A policy built from a policy's config has the same config."""
    config = PointerPolicy(n_nodes=4, dim=8, glimpse="unvisited", local=True, damp=3).config
    assert build_policy(config).config == config
    config = AttentionPolicy(dim=8, n_heads=2, n_layers=1, ff=16, local=False).config
    assert build_policy(config).config == config


def test_unknown_model_or_bad_arguments_are_input_errors():
    """The getter lists the valid names; arguments the class does not take are one clear error."""
    with pytest.raises(InputError, match="model must be one of 'drl', 'am', 'local', got 'lstm'"):
        get_policy("lstm")
    with pytest.raises(InputError, match="model must be one of"):
        build_policy({"dim": 8})
    with pytest.raises(InputError, match="bad model config"):
        build_policy({"model": "am", "width": 8})


def _learned_imports(path) -> set[str]:
    """The modules of the learned package that ``path`` imports (at any depth in the file)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith(PACKAGE + "."):
            found.add(node.module.removeprefix(PACKAGE + "."))
        elif isinstance(node, ast.Import):
            found |= {a.name.removeprefix(PACKAGE + ".") for a in node.names
                      if a.name.startswith(PACKAGE + ".")}
    return found


def test_learned_modules_import_without_a_cycle():
    """The imports between the learned modules (lazy ones included) form no cycle: the
    policies are imported by the registry, never the other way round."""
    graph = {p.stem: _learned_imports(p) for p in LEARNED.glob("*.py") if p.stem != "__init__"}
    assert "rl_common" not in graph and graph["policies"] >= {"drl", "am"}
    assert not (graph["drl"] | graph["am"] | graph["local"]) & {"policies", "checkpoint", "solver", "train",
                                                                "recipes", "imitation"}
    done: set[str] = set()

    def visit(name: str, path: tuple[str, ...]) -> None:
        assert name not in path, f"import cycle: {' -> '.join((*path, name))}"
        if name in done:
            return
        for dep in graph.get(name, ()):
            visit(dep, (*path, name))
        done.add(name)

    for module in graph:
        visit(module, ())
