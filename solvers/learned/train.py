"""The training loop of the learned policies: REINFORCE (paper Algorithm 1) with a baseline.

What to train comes from a :class:`~gtsp_bench.solvers.learned.recipes.TrainConfig` (a named
recipe, :func:`~gtsp_bench.solvers.learned.recipes.get_recipe`): the policy, its baseline
(:mod:`~gtsp_bench.solvers.learned.baselines`: the paper's critic, or POMO's shared mean), the
head rule of the reward, and ``direction`` (beyond the paper: a term that prices each sampled
tour flown backwards too and moves the odds of its first step toward the cheaper direction).
The actor gets one Adam, a learning baseline another, as the paper. Data are drawn fresh each
step from :func:`gtsp_bench.generator.generate_batch`, omega uniform in [0, 1] per instance
unless fixed, and priced by the shared evaluator's quantities.

    from gtsp_bench.solvers.learned.recipes import get_recipe
    from gtsp_bench.solvers.learned.train import train
    train(get_recipe("drl", seed=3), "my_drl.pt")    # = gtsp-bench train --model drl --seed 3

Given ``-o CKPT`` (e.g. ``drl.pt``), training writes, atomically:

* ``CKPT``: the policy with the best validation energy so far (``--keep best``, the default) or
  the latest validated one (``--keep last``), as config + state_dict;
* ``CKPT.json`` (``drl.json``): command, seed, steps, wall time, validation score, config;
* ``CKPT.train.csv`` (``drl.train.csv``): the log, columns ``step,loss,reward,val_energy,wall_s``
  then ``val_gap_pct,critic_loss``; ``loss`` is the actor's loss, ``reward`` the mean -E (J) of
  the sampled tours since the previous row, ``val_energy`` the mean greedy energy (J) on the
  fixed validation set;
* ``CKPT.state.pt`` (``drl.state.pt``): everything needed to resume (weights, optimisers, random
  states, step, log rows), at every validation. ``--resume`` continues from it.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from gtsp_bench.solvers.learned.baselines import get_baseline
from gtsp_bench.solvers.learned.checkpoint import save_policy
from gtsp_bench.solvers.learned.env import COST_SCALE, EnvBatch, choose_heads, make_env, tour_cost
from gtsp_bench.solvers.learned.oracles import exact_by_enumeration
from gtsp_bench.solvers.learned.policies import build_policy
from gtsp_bench.solvers.learned.recipes import TrainConfig
from torch import nn

from gtsp_bench.data.io import atomic_write_bytes, atomic_write_text
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_batch

#: Seed of the fixed validation set (never used for training or testing).
VAL_SEED = 918_273
#: Validation sets up to this K also get the exact optimum (by enumeration) and a gap column.
MAX_EXACT_K = 6
LOG_COLUMNS = ("step", "loss", "reward", "val_energy", "wall_s", "val_gap_pct", "critic_loss")


def policy_config(cfg: TrainConfig) -> dict[str, Any]:
    """The config of the policy ``cfg`` trains: its ``model_options``, and for drl the cluster
    size ``n_nodes`` = ``nodes`` and, with the local term, ``damp`` = the training K (the pointer
    is damped only beyond it), unless the options give them."""
    options = dict(cfg.model_options)
    if cfg.model == "drl":
        options.setdefault("n_nodes", cfg.nodes)
        if options.get("local"):
            options.setdefault("damp", cfg.clusters)
    return {"model": cfg.model, **options}


def output_paths(ckpt: str | Path) -> dict[str, Path]:
    """The files of a training run, from the policy file's path."""
    p = Path(ckpt)
    stem = p.with_suffix("")
    return {"policy": p, "meta": stem.with_suffix(".json"),
            "log": Path(f"{stem}.train.csv"), "state": Path(f"{stem}.state.pt")}


def validation_env(cfg: TrainConfig) -> EnvBatch:
    """The fixed validation set: seeded coordinates, omega evenly spread over [0, 1]."""
    rng = np.random.default_rng([VAL_SEED, cfg.clusters, cfg.nodes])
    coords = generate_batch(rng, cfg.val_size, cfg.clusters, cfg.nodes)
    omega = cfg.omega if cfg.omega is not None else np.linspace(0.0, 1.0, cfg.val_size)
    return make_env(coords, omega)


def greedy_cost(model: nn.Module, env: EnvBatch, rule: str, chunk: int = 256) -> torch.Tensor:
    """Cost ``(B,)`` of the model's greedy decoding (best of its greedy tours per instance)."""
    out = []
    b = env.shape[0]
    with torch.inference_mode():
        for i in range(0, b, chunk):
            sub = env.rows(i, i + chunk)
            order, _ = model.decode(sub, "greedy")
            m = sub.shape[0]
            rep = sub.repeat(order.shape[0] // m)
            cost = tour_cost(rep, order, choose_heads(rep, order, rule)).view(m, -1)
            out.append(cost.min(1).values)
    return torch.cat(out)


class Trainer:
    """One training run; :meth:`run` trains, validates, logs and checkpoints."""

    def __init__(self, cfg: TrainConfig, output: str | Path, *, resume: bool = False) -> None:
        self.cfg = cfg
        self.paths = output_paths(output)
        if self.paths["policy"].suffix != ".pt":
            raise InputError(f"{output}: the policy file must end in .pt")
        torch.set_num_threads(cfg.threads)
        torch.manual_seed(cfg.seed)
        self.model = build_policy(policy_config(cfg))
        self.baseline = get_baseline(cfg.baseline, self.model)
        own = self.baseline.parameters()
        own_ids = {id(p) for p in own}
        actor = [p for p in self.model.parameters() if id(p) not in own_ids]
        self.optims = [torch.optim.Adam(actor, lr=cfg.lr)]
        if own:
            self.optims.append(torch.optim.Adam(own, lr=cfg.lr))
        self.rng = np.random.default_rng([cfg.seed, 1])
        self.gen = torch.Generator().manual_seed(cfg.seed)
        self.step = 0
        self.wall = 0.0
        self.rows: list[dict[str, Any]] = []
        self.best: float = math.inf
        self.best_step = 0
        self.val = validation_env(cfg)
        self.val_opt = exact_by_enumeration(self.val) if cfg.clusters <= MAX_EXACT_K else None
        state = self.paths["state"]
        if resume:
            self._load_state()
        elif state.exists():
            raise InputError(f"{state} exists: add --resume to continue that run, or remove it")

    # ------------------------------------------------------------------ state
    def _load_state(self) -> None:
        path = self.paths["state"]
        if not path.is_file():
            raise InputError(f"{path}: no training state to resume")
        try:
            s = torch.load(path, map_location="cpu", weights_only=True)
        except Exception:
            raise InputError(f"{path}: corrupt training state") from None
        if s.get("identity") != json.loads(json.dumps(self.cfg.identity())):
            raise InputError(f"{path}: saved by a run with other settings; cannot resume with these")
        self.model.load_state_dict(s["model"])
        for opt, st in zip(self.optims, s["optims"], strict=True):
            opt.load_state_dict(st)
        self.rng.bit_generator.state = json.loads(s["rng"])
        self.gen.set_state(s["gen"])
        self.step, self.wall = int(s["step"]), float(s["wall"])
        self.best, self.best_step = float(s["best"]), int(s["best_step"])
        self.rows = json.loads(s["rows"])
        # the state is written before the log: a kill between the two leaves the log a row behind
        self._write_log()

    def _save_state(self) -> None:
        state = {
            "identity": json.loads(json.dumps(self.cfg.identity())),
            "model": self.model.state_dict(),
            "optims": [o.state_dict() for o in self.optims],
            "rng": json.dumps(self.rng.bit_generator.state),
            "gen": self.gen.get_state(),
            "step": self.step, "wall": self.wall, "best": self.best, "best_step": self.best_step,
            "rows": json.dumps(self.rows),
        }
        buf = io.BytesIO()
        torch.save(state, buf)
        atomic_write_bytes(self.paths["state"], buf.getvalue())
        self._write_log()

    def _write_log(self) -> None:
        out = io.StringIO()
        writer = csv.DictWriter(out, fieldnames=LOG_COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(self.rows)
        atomic_write_text(self.paths["log"], out.getvalue())

    def _write_meta(self, val_energy: float, val_gap: float | None) -> None:
        meta = {
            "model": self.cfg.model,
            "command": self.cfg.command(self.paths["policy"]),
            "seed": self.cfg.seed,
            "steps": self.best_step,
            "steps_trained": self.step,
            "wall_s": round(self.wall, 1),
            "val_energy": val_energy,
            "val_gap_pct": val_gap,
            "validation": {"seed": VAL_SEED, "instances": self.cfg.val_size,
                           "clusters": self.cfg.clusters, "nodes": self.cfg.nodes,
                           "omega": self.cfg.omega if self.cfg.omega is not None else "linspace(0, 1)",
                           "decoding": "greedy", "heads": self.cfg.heads},
            "config": self.model.config,
            "train": dataclasses.asdict(self.cfg),
            "torch": torch.__version__,
        }
        atomic_write_text(self.paths["meta"], json.dumps(meta, indent=2) + "\n")

    # ------------------------------------------------------------------ training
    def batch_env(self) -> EnvBatch:
        """A fresh training batch."""
        cfg = self.cfg
        coords = generate_batch(self.rng, cfg.batch, cfg.clusters, cfg.nodes)
        omega = cfg.omega if cfg.omega is not None else self.rng.uniform(0.0, 1.0, cfg.batch)
        return make_env(coords, omega)

    def train_step(self) -> tuple[float, float, float]:
        """One gradient step; returns (actor loss, mean reward in J, baseline loss or NaN)."""
        env = self.batch_env()
        self.model.train()
        if self.cfg.direction:  # the first step's distribution comes with the sample
            order, logp, first = self.model.decode_first(env, "sample", generator=self.gen)
        else:
            order, logp = self.model.decode(env, "sample", generator=self.gen)
        rep = env.repeat(order.shape[0] // env.shape[0])
        with torch.no_grad():
            cost = tour_cost(rep, order, choose_heads(rep, order, self.cfg.heads))
        c = (cost / COST_SCALE).float()
        advantage, baseline_loss = self.baseline(env, c)
        loss = (advantage * logp).mean()
        if self.cfg.direction:
            loss = loss + self._direction_loss(env, order, c, first)
        total = loss if baseline_loss is None else loss + baseline_loss
        for opt in self.optims:
            opt.zero_grad(set_to_none=True)
        total.backward()
        nn.utils.clip_grad_norm_(self.model.parameters(), self.cfg.grad_clip)
        for opt in self.optims:
            opt.step()
        critic_loss = math.nan if baseline_loss is None else float(baseline_loss.detach())
        return float(loss.detach()), -float(cost.mean()), critic_loss

    def _direction_loss(self, env: EnvBatch, order: torch.Tensor, c: torch.Tensor,
                        first: torch.Tensor) -> torch.Tensor:
        """The direction term: prefer the cheaper of each sampled tour and the same tour flown
        backwards, through the log-odds of their first steps.

        A tour's first step is its choice of direction: both directions visit the same clusters
        and, under the paper's head rule, differ in cost only through the heads the rule picks,
        a signal the critic's baseline is too noisy to carry (the gap between greedy decoding
        and ``reverse=true``). With ``lp`` the log-probabilities of the two first steps (taken
        at the same state) and ``s = sign(c_rev - c)``, the term is
        ``mean(|c - c_rev| * softplus(-s (lp - lp_rev)))``, a logistic loss weighted by what the
        wrong direction costs: it pulls hardest where the policy prefers the costlier direction
        and fades once it prefers the cheaper one. ``first`` ``(B, K)``: the first step's
        log-probabilities (:meth:`gtsp_bench.solvers.learned.drl.PointerPolicy.decode_first`).
        """
        rev = order.flip(-1)
        lp, lp_rev = first.gather(1, torch.stack([order[:, 0], rev[:, 0]], 1)).unbind(1)
        with torch.no_grad():
            c_rev = (tour_cost(env, rev, choose_heads(env, rev, self.cfg.heads))
                     / COST_SCALE).float()
        diff = c_rev - c  # > 0: the sampled direction is the cheaper one
        return (diff.abs() * nn.functional.softplus(-diff.sign() * (lp - lp_rev))).mean()

    def validate(self) -> tuple[float, float | None]:
        """Mean greedy energy (J) on the validation set, and the mean gap (%) when known."""
        self.model.eval()
        cost = greedy_cost(self.model, self.val, self.cfg.heads)
        gap = None
        if self.val_opt is not None:
            gap = float(((cost / self.val_opt - 1) * 100).mean())
        return float(cost.mean()), gap

    def run(self, progress: bool = True) -> dict[str, Any]:
        """Train until ``steps`` or ``max_time``; returns the final JSON metadata."""
        from tqdm import tqdm

        cfg = self.cfg
        if self.step == 0 and not self.rows:
            val_energy, gap = self.validate()
            self._record_best(val_energy, gap)
            self.rows.append({"step": 0, "loss": "", "reward": "", "val_energy": val_energy,
                              "wall_s": 0.0, "val_gap_pct": _fmt(gap), "critic_loss": ""})
            self._save_state()
        bar = tqdm(total=cfg.steps, initial=self.step, disable=not progress, unit="step",
                   dynamic_ncols=True)
        window: list[tuple[float, float, float]] = []
        start = time.perf_counter() - self.wall
        try:
            while self.step < cfg.steps:
                if cfg.max_time is not None and self.wall >= cfg.max_time:
                    break
                window.append(self.train_step())
                self.step += 1
                self.wall = time.perf_counter() - start
                bar.update(1)
                last = self.step == cfg.steps or (cfg.max_time is not None and self.wall >= cfg.max_time)
                if self.step % cfg.log_every == 0 or last:
                    self._log(window, force_val=last)
                    window = []
                    bar.set_postfix(reward=f"{self.rows[-1]['reward']:.1f}",
                                    val=f"{self.best:.1f}")
        finally:
            bar.close()
        return json.loads(self.paths["meta"].read_text())

    def _log(self, window: list[tuple[float, float, float]], force_val: bool = False) -> None:
        row: dict[str, Any] = {"step": self.step, "wall_s": round(self.wall, 2), "val_energy": "",
                               "val_gap_pct": ""}
        if window:
            arr = np.array(window)
            row.update(loss=arr[:, 0].mean(), reward=arr[:, 1].mean(),
                       critic_loss="" if np.isnan(arr[:, 2]).all() else arr[:, 2].mean())
        else:
            row.update(loss="", reward="", critic_loss="")
        if force_val or self.step % self.cfg.val_every == 0 or self.step == self.cfg.steps:
            val_energy, gap = self.validate()
            row.update(val_energy=val_energy, val_gap_pct=_fmt(gap))
            self._record_best(val_energy, gap)
            self.rows.append(row)
            self._save_state()
        else:
            self.rows.append(row)

    def _record_best(self, val_energy: float, gap: float | None) -> None:
        if val_energy < self.best or self.cfg.keep == "last":
            self.best, self.best_step = val_energy, self.step
            save_policy(self.model, self.paths["policy"])
            self._write_meta(val_energy, gap)
        else:  # keep the best policy, update the run's progress
            meta = json.loads(self.paths["meta"].read_text())
            meta.update(steps_trained=self.step, wall_s=round(self.wall, 1))
            atomic_write_text(self.paths["meta"], json.dumps(meta, indent=2) + "\n")


def _fmt(x: float | None) -> Any:
    return "" if x is None else x


def train(cfg: TrainConfig, output: str | Path, *, resume: bool = False,
          progress: bool = True) -> dict[str, Any]:
    """Train a policy; see the module docstring for the files written. Returns the metadata."""
    return Trainer(cfg, output, resume=resume).run(progress=progress)
