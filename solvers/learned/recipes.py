"""Named training recipes: every setting of a training run, in one place per recipe.

A recipe is a :class:`TrainConfig` in :data:`RECIPES`. Both ways to train resolve a name here:
``get_recipe("drl", seed=3)`` from Python, ``gtsp-bench train --model drl --seed 3`` from the
command line (its switches override fields; every default is the recipe's). A test checks that
the two build the identical config for every name, and that the recorded command line rebuilds
the config it came from.

* ``drl``: the shipped ``checkpoints/drl.pt``: the paper's pointer with the glimpse over
  unvisited clusters, the learned term of the UAV's location with the paper rule's energy
  features, and the direction term in the loss; the critic baseline, the paper's head rule.
* ``drl-paper``: the paper's plain recipe (section IV and Algorithm 1): its pointer (glimpse
  over every element, no location term), REINFORCE with the critic, 40,000 steps of 256
  instances at lr 1e-4, K = 4, the paper's head rule.
* ``am``: the shipped ``checkpoints/am.pt``: the attention model with POMO starts and the
  shared baseline, optimal heads in the reward, batch 64, keeping the last validated policy.

The shipped models were trained with seed 2 for 2280 s (38 minutes) of wall time on one torch
thread; ``drl`` and ``am`` carry those settings, so ``gtsp-bench train --model drl -o drl.pt``
repeats that run (up to the speed of the machine: the time budget decides the last step).
``drl-paper`` has the same seed and runs its 40,000 steps with no time budget.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gtsp_bench.solvers.learned.baselines import BASELINES
from gtsp_bench.solvers.learned.env import HEAD_RULES
from gtsp_bench.solvers.learned.policies import get_policy

from gtsp_bench.checks import (
    check_bool,
    check_choice,
    check_float,
    check_int,
    check_mapping,
    check_omega,
    check_seed,
)
from gtsp_bench.errors import InputError
from gtsp_bench.generator import check_generator_args

#: Which policy file a run keeps: the best validation energy so far, or the last validated one.
KEEP = ("best", "last")
#: The recipe ``gtsp-bench train`` uses without ``--model``.
DEFAULT_RECIPE = "drl"


@dataclass(frozen=True)
class TrainConfig:
    """Settings of one training run: a recipe, or a recipe with some fields changed.

    Every field is recorded in the JSON beside the policy file (``"train"``). ``gtsp-bench
    train --model RECIPE`` picks the recipe; a switch of the same name sets each other field but
    ``model``, ``baseline`` and ``grad_clip`` (the recipe's), ``log_every`` (with
    ``--val-every``: its greatest common divisor with the recipe's) and ``model_options``
    (drl: ``--glimpse``, ``--local``, ``--energy``).

    Attributes
    ----------
    recipe
        Name of the recipe in :data:`RECIPES` these settings start from: the recorded command
        line (:meth:`command`) is ``gtsp-bench train --model RECIPE`` plus every switch.
    model
        The policy trained, a name in :data:`gtsp_bench.solvers.learned.policies.POLICIES`
        (``drl``: the pointer network; ``am``: the attention model).
    model_options
        Arguments of the policy's constructor. drl: ``glimpse`` (``all`` | ``unvisited``),
        ``local``, ``energy``, ``dim``; its ``n_nodes`` is ``nodes`` and, with ``local``, its
        ``damp`` the training K, unless given. am: ``dim``, ``n_heads``, ``n_layers``, ``ff``,
        ``local``.
    baseline
        REINFORCE baseline, a name in :data:`gtsp_bench.solvers.learned.baselines.BASELINES`
        that the policy supports (drl: ``critic``; am: ``pomo``).
    heads
        Head rule in the reward and in validation (``paper`` | ``optimal``).
    direction
        drl only: also price each sampled tour flown backwards and move the odds of its first
        step toward the cheaper direction (:meth:`Trainer._direction_loss
        <gtsp_bench.solvers.learned.train.Trainer._direction_loss>`).
    clusters
        K of the training (and validation) instances.
    nodes
        N, the nodes per cluster.
    steps
        Gradient steps to train (the run may stop earlier at ``max_time``).
    batch
        Instances per step (am decodes K tours of each).
    lr
        Adam's learning rate (actor and, with its own optimiser, the critic).
    grad_clip
        Gradients are clipped to this total norm each step.
    omega
        Train for this one omega; ``None``: omega uniform in [0, 1] per instance (validation:
        evenly spread over [0, 1]).
    seed
        Seed of the weights, the training instances and the sampling.
    max_time
        Stop after this many seconds of training wall time; ``None``: after ``steps``.
    threads
        torch threads.
    keep
        Policy kept in the file: ``best`` validation energy or the ``last`` validated one.
    val_every
        Validate (and write the resume state) every this many steps; a multiple of
        ``log_every``.
    val_size
        Instances in the fixed validation set.
    log_every
        A log row every this many steps.
    """

    recipe: str
    model: str
    model_options: dict[str, Any]
    baseline: str
    heads: str
    direction: bool
    clusters: int
    nodes: int
    steps: int
    batch: int
    lr: float
    grad_clip: float
    omega: float | None
    seed: int
    max_time: float | None
    threads: int
    keep: str
    val_every: int
    val_size: int
    log_every: int

    def __post_init__(self) -> None:
        # a copy of its own: changing it leaves the recipe (or the caller's dict) alone
        object.__setattr__(self, "model_options", check_mapping("model_options", self.model_options))
        policy = get_policy(self.model)
        check_choice(f"baseline of the {self.model} policy", self.baseline,
                     tuple(b for b in policy.baselines if b in BASELINES))
        check_choice("heads", self.heads, tuple(HEAD_RULES))
        if check_bool("direction", self.direction) and not hasattr(policy, "decode_first"):
            raise InputError("--direction is a training option of the drl model only")
        check_generator_args(self.clusters, self.nodes, 50.0, 1000.0)
        if self.clusters < 2:
            raise InputError("training needs at least 2 clusters")
        for name in ("steps", "batch", "val_every", "val_size", "log_every", "threads"):
            check_int(name, getattr(self, name), 1)
        check_float("learning rate", self.lr, 0.0, math.inf)
        check_float("grad_clip", self.grad_clip, 0.0, math.inf)
        if self.omega is not None:
            check_omega(self.omega)
        check_seed(self.seed)
        if self.max_time is not None:
            check_float("max time", self.max_time, 0.0, math.inf)
        check_choice("keep", self.keep, KEEP)
        if self.val_every % self.log_every:
            raise InputError("val_every must be a multiple of log_every")

    def command(self, output: str | Path) -> str:
        """The ``gtsp-bench train`` command line that rebuilds this config: the recipe and every
        switch spelled out (a recipe's defaults may change)."""
        parts = ["gtsp-bench train", f"--model {self.recipe}", f"--clusters {self.clusters}",
                 f"--nodes {self.nodes}", f"--steps {self.steps}", f"--batch {self.batch}",
                 f"--lr {_number(self.lr)}", f"--seed {self.seed}", f"--heads {self.heads}",
                 f"--threads {self.threads}", f"--keep {self.keep}",
                 f"--val-every {self.val_every}", f"--val-size {self.val_size}"]
        if self.model == "drl":
            opts = self.model_options
            parts.append(f"--glimpse {opts.get('glimpse', 'all')}")
            parts.append("--local" if opts.get("local") else "--no-local")
            if opts.get("local"):
                parts.append("--energy" if opts.get("energy") else "--no-energy")
            parts.append("--direction" if self.direction else "--no-direction")
        parts.append(f"--omega {_number(self.omega)}")
        parts.append(f"--max-time {_number(self.max_time)}")
        return " ".join(parts) + f" -o {output}"

    def identity(self) -> dict[str, Any]:
        """Settings that a resumed run must share with the run it continues."""
        d = dataclasses.asdict(self)
        for k in ("recipe", "steps", "max_time", "threads", "keep"):
            d.pop(k)
        return d


def _number(x: float | None) -> str:
    """``x`` as short as it reads back exactly (``none`` for ``None``)."""
    if x is None:
        return "none"
    short = f"{x:g}"
    return short if float(short) == x else repr(float(x))


#: The named recipes (see the module docstring).
RECIPES: dict[str, TrainConfig] = {
    "drl": TrainConfig(
        recipe="drl", model="drl",
        model_options={"glimpse": "unvisited", "local": True, "energy": True},
        baseline="critic", heads="paper", direction=True,
        clusters=4, nodes=20, steps=40_000, batch=256, lr=1e-4, grad_clip=1.0, omega=None,
        seed=2, max_time=2280.0, threads=1, keep="best",
        val_every=250, val_size=512, log_every=50,
    ),
    "drl-paper": TrainConfig(
        recipe="drl-paper", model="drl",
        model_options={"glimpse": "all"},
        baseline="critic", heads="paper", direction=False,
        clusters=4, nodes=20, steps=40_000, batch=256, lr=1e-4, grad_clip=1.0, omega=None,
        seed=2, max_time=None, threads=1, keep="best",
        val_every=250, val_size=512, log_every=50,
    ),
    "am": TrainConfig(
        recipe="am", model="am",
        model_options={},
        baseline="pomo", heads="optimal", direction=False,
        clusters=4, nodes=20, steps=40_000, batch=64, lr=1e-4, grad_clip=1.0, omega=None,
        seed=2, max_time=2280.0, threads=1, keep="last",
        val_every=250, val_size=512, log_every=50,
    ),
}


def get_recipe(name: str, **overrides: Any) -> TrainConfig:
    """The recipe ``name`` with the given fields changed (all checked again).

    Raises
    ------
    InputError
        An unknown recipe (listing the valid names), an unknown field, or a bad value.
    """
    base = RECIPES[check_choice("recipe", name, tuple(RECIPES))]
    fields = {f.name for f in dataclasses.fields(TrainConfig)} - {"recipe"}
    unknown = sorted(set(overrides) - fields)
    if unknown:
        raise InputError(f"unknown training setting(s) {', '.join(unknown)} "
                         f"(valid: {', '.join(sorted(fields))})")
    return dataclasses.replace(base, **overrides)
