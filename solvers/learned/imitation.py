"""Imitation training of the local-view policy (:mod:`~.local`) on near-optimal tours.

REINFORCE needs many sampled tours per useful gradient; a CPU budget of under an hour is far
better spent imitating good tours (as LEHD and BQ-NCO train). A run:

1. **Labels** (:mod:`~.labels`): for each ``(K, count, area)`` of the recipe's mix, instances
   ``instance_set(count, K, label_seed, area=area)`` (a seed no test set uses), omega of instance
   i drawn from ``[label_seed, K, i]`` uniform in ``[0, omega_max]``; for a
   ``(K, count, area, "tiled")`` entry, :func:`~.tiled.tiled_set` instances (clusters that tile
   the plane, as GTSPLIB's) at omega 0. Each is solved by ``lns`` with ``stop_at_convergence``.
   Labels and the validation sets' reference values are cached (``CKPT.labels.npz``; reused
   when the mix matches, so a second run skips them).
2. **States**: every label tour is walked from the depot, forwards and backwards (both
   directions cost the same with optimal heads), through the same :class:`~.local.Walk` that
   decoding uses; each step's view and the position of the tour's next cluster in it is one
   sample (steps whose next cluster is outside the view, or with one candidate left, are left out).
3. **Training**: cross-entropy on the next cluster, each sample's vectors turned by a random
   rotation and mirror (the problem's symmetry), Adam with a cosine learning rate over the time
   budget, optionally an exponential average of the weights (``ema``). Validation: greedy
   decoding (one start, optimal heads) on fixed sets (K = 50, or K = 20-200 for the ``l4``
   recipes) against ``lns``, of the averaged weights where there are; the policy with the best
   validation gap (the mean over the sets) is kept.

Files, beside ``-o CKPT``: ``CKPT`` (the policy), ``CKPT.json`` (command, mix, times, scores,
config), ``CKPT.imitation.csv`` (``step,loss,accuracy,lr,val_gap_pct,wall_s``; not named
``.train.csv``: the runner's training figure reads those, REINFORCE logs of reward and energy).

    python -m gtsp_bench.solvers.learned.imitation --recipe local -o local.pt

On a machine with a GPU and many cores, ``--device cuda --workers 15`` solves the labels and walks
the states in 15 processes and trains on the GPU (the ``local-gpu`` recipes are sized for that);
the policy file is saved with CPU tensors either way.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from gtsp_bench.solvers.learned.checkpoint import save_policy
from gtsp_bench.solvers.learned.env import EnvBatch, env_from_instances, optimal_heads_batch
from gtsp_bench.solvers.learned.labels import (
    VAL_SEED,
    Entry,
    fork_pool,
    label_set,
    load_or_solve_labels,
    parse_entry,
    validation_set,
)
from gtsp_bench.solvers.learned.local import LocalPolicy, Walk, _flight_per_m, turn
from torch import nn

from gtsp_bench.checks import arg_float, arg_seed, check_choice, check_float, check_int, check_seed
from gtsp_bench.data.io import atomic_write_text
from gtsp_bench.errors import InputError, OneLineParser

LOG_COLUMNS = ("step", "loss", "accuracy", "lr", "val_gap_pct", "wall_s")


@dataclass(frozen=True)
class ImitationConfig:
    """Settings of one imitation run.

    Attributes
    ----------
    recipe
        Name in :data:`RECIPES` these settings start from.
    mix
        ``(K, instances, area)`` label sets: K clusters, how many instances, square side (m); a
        fourth element ``"tiled"`` makes a set of :mod:`~.tiled` instances.
    nodes
        N, nodes per cluster.
    omega_max
        Label omegas are uniform in ``[0, omega_max]``.
    label_seed
        Instance-set seed of the labels (no test set may use it).
    model_options
        :class:`~.local.LocalPolicy` arguments.
    batch, lr, max_time, steps, seed, threads
        Samples per step, peak learning rate, training wall budget (s), step cap, seed, torch
        threads.
    ema
        Decay of an exponential moving average of the weights (0: none). With it, validation
        and the policy file use the averaged weights (torch's ``AveragedModel``).
    val
        ``(K, instances, area)`` of the validation set (omega 0.3 and 0.6 in turn), or a tiled
        entry (omega 0); or a tuple of such entries, whose mean gaps are averaged (each K
        counts the same). Stored as a tuple of entries.
    val_every, log_every
        Steps between validations and between log rows.
    """

    recipe: str
    mix: tuple[Entry, ...]
    nodes: int = 20
    omega_max: float = 0.9
    label_seed: int = 71_000
    model_options: dict[str, Any] = field(default_factory=dict)
    batch: int = 256
    lr: float = 1e-3
    max_time: float = 1800.0
    steps: int = 1_000_000
    seed: int = 0
    threads: int = 1
    ema: float = 0.0
    val: Entry | tuple[Entry, ...] = (50, 24, 1500.0)
    val_every: int = 500
    log_every: int = 100

    def __post_init__(self) -> None:
        if not self.mix:
            raise InputError("the label mix is empty")
        if not self.val:
            raise InputError("the validation set is empty")
        val = (self.val,) if not isinstance(self.val[0], (tuple, list)) else self.val  # one entry
        object.__setattr__(self, "val", tuple(tuple(e) for e in val))
        for e in (*self.mix, *self.val):
            if len(e) not in (3, 4) or (len(e) == 4 and e[3] != "tiled"):
                raise InputError(f"a label set is (K, instances, area[, 'tiled']), got {e!r}")
            k, n, area, _ = parse_entry(e)
            check_int("K", k, 2)
            check_int("instances", n, 1)
            check_float("area", area, 0.0, math.inf)
        check_float("omega_max", self.omega_max, 0.0, 1.0, open_low=False)
        for name in ("nodes", "batch", "steps", "threads", "val_every", "log_every"):
            check_int(name, getattr(self, name), 1)
        check_float("learning rate", self.lr, 0.0, math.inf)
        check_float("max time", self.max_time, 0.0, math.inf)
        if check_float("ema", self.ema, 0.0, 1.0, open_low=False) == 1.0:
            raise InputError("ema must be below 1 (0: no averaging)")
        check_seed(self.seed)
        check_seed(self.label_seed)
        if self.label_seed in (1, 5_000, 6_000):
            raise InputError(f"label seed {self.label_seed} is a test set's seed")

    def command(self, output: str | Path, device: str = "cpu", workers: int = 1) -> str:
        """The command line that repeats this run (on ``device``, labels in ``workers``)."""
        extra = (f" --device {device}" if device != "cpu" else "") + (
            f" --workers {workers}" if workers > 1 else "")
        return (f"python -m gtsp_bench.solvers.learned.imitation --recipe {self.recipe} "
                f"--max-time {self.max_time:g} --seed {self.seed}{extra} -o {output}")


_GPU_MIX = ((10, 1000, 1000.0), (20, 2500, 1000.0), (30, 1500, 1200.0), (50, 2000, 1500.0),
            (100, 400, 2000.0))
_TILED_MIX = ((20, 2000, 1000.0, "tiled"), (40, 1500, 1000.0, "tiled"),
              (80, 600, 1000.0, "tiled"), (120, 150, 1000.0, "tiled"))
#: Validation from K = 20 to 200 (the policy kept is the best over all four sets).
_VAL_K = ((20, 24, 1000.0), (50, 24, 1500.0), (100, 16, 2000.0), (200, 8, 3000.0))
_L4 = {"dim": 128, "n_layers": 4, "ff": 256}

#: The named recipes. ``local``: the shipped ``checkpoints/local.pt``; ``local-small``: a short
#: run on fewer labels (the fallback, and a quick check that training works).
RECIPES: dict[str, ImitationConfig] = {
    "local": ImitationConfig(
        recipe="local",
        mix=((10, 1000, 1000.0), (20, 2500, 1000.0), (30, 1500, 1200.0), (50, 700, 1500.0),
             (100, 40, 2000.0)),
        max_time=1620.0,
    ),
    # GPU runs: more labels at K >= 50, bigger batches, labels and states in
    # 15 processes (``--device cuda --workers 15``); the same policy size as ``local``.
    "local-gpu": ImitationConfig(
        recipe="local-gpu",
        mix=_GPU_MIX,
        batch=1024, lr=1.5e-3, max_time=165.0, val_every=2000, log_every=200,
    ),
    # the same with a wider, deeper policy (dearer on a CPU)
    "local-gpu-l3": ImitationConfig(
        recipe="local-gpu-l3",
        mix=_GPU_MIX,
        model_options={"dim": 96, "n_layers": 3, "ff": 192},
        batch=1024, lr=1e-3, max_time=165.0, val_every=2000, log_every=200,
    ),
    # wider and deeper again, its weights averaged (ema), validated from K = 20 to 200
    "local-gpu-l4": ImitationConfig(
        recipe="local-gpu-l4",
        mix=_GPU_MIX, model_options=_L4, ema=0.999, val=_VAL_K,
        batch=1024, lr=1e-3, max_time=400.0, val_every=2000, log_every=200,
    ),
    # the same on the UAV mix and the tiled one together (for GTSPLIB's planar files too)
    "local-gpu-l4-tiled": ImitationConfig(
        recipe="local-gpu-l4-tiled",
        mix=_GPU_MIX + _TILED_MIX, model_options=_L4, ema=0.999,
        val=(*_VAL_K, (60, 24, 1000.0, "tiled")),
        batch=1024, lr=1e-3, max_time=400.0, val_every=2000, log_every=200,
    ),
    # distance-only problems (GTSPLIB's planar files): clusters that tile the plane, omega 0
    "local-tiled": ImitationConfig(
        recipe="local-tiled",
        mix=_TILED_MIX,
        val=(60, 24, 1000.0, "tiled"),
        max_time=1200.0,
    ),
    "local-small": ImitationConfig(
        recipe="local-small",
        mix=((10, 300, 1000.0), (20, 600, 1000.0), (30, 300, 1200.0)),
        max_time=300.0,
    ),
}


def get_recipe(name: str, **overrides: Any) -> ImitationConfig:
    """The recipe ``name`` with fields changed (checked again)."""
    base = RECIPES[check_choice("recipe", name, tuple(RECIPES))]
    return dataclasses.replace(base, **overrides)


# ---------------------------------------------------------------------- states
@dataclass(frozen=True)
class Samples:
    """Training states: view features, the candidate mask and the target position in the view."""

    cand_vec: torch.Tensor
    cand_sc: torch.Tensor
    ctx_vec: torch.Tensor
    ctx_sc: torch.Tensor
    mask: torch.Tensor
    target: torch.Tensor

    def __len__(self) -> int:
        return len(self.target)

    def take(self, idx: torch.Tensor) -> Samples:
        return Samples(*(getattr(self, f.name)[idx] for f in dataclasses.fields(self)))

    @staticmethod
    def join(parts: Sequence[Samples]) -> Samples:
        return Samples(*(torch.cat([getattr(p, f.name) for p in parts])
                         for f in dataclasses.fields(Samples)))


def walk_states(env: EnvBatch, orders: torch.Tensor, k: int) -> tuple[Samples, float]:
    """The samples of walking ``orders`` ``(B, K)`` on ``env`` and the share of steps whose next
    cluster was in the view (of those with at least two candidates)."""
    walk = Walk(env, 1, k, _flight_per_m(env))
    parts, seen, total = [], 0, 0
    for t in range(orders.shape[1]):
        v = walk.view()
        target = orders[:, t]
        hit = v.cluster == target[:, None]
        pos = hit.float().argmax(1)
        ok = hit.any(1) & (v.mask.sum(1) >= 2)
        total += int((v.mask.sum(1) >= 2).sum())
        seen += int(ok.sum())
        if ok.any():
            parts.append(Samples(v.cand_vec[ok], v.cand_sc[ok], v.ctx_vec[ok], v.ctx_sc[ok],
                                 v.mask[ok], pos[ok]))
        walk.goto(target)
    return Samples.join(parts), seen / max(total, 1)


def _chunk_states(task: tuple[ImitationConfig, Entry, int, np.ndarray, int],
                  ) -> tuple[list[Samples], float]:
    """The states of label tours ``lo .. lo + len(orders)`` of one mix entry, both directions."""
    cfg, e, lo, orders, k = task
    torch.set_num_threads(1)
    kk, n, area, tiled = parse_entry(e)
    insts, omegas = label_set(kk, n, area, cfg.label_seed, cfg.nodes, cfg.omega_max, tiled)
    env = env_from_instances(insts[lo:lo + len(orders)], omegas[lo:lo + len(orders)].tolist())
    o = torch.from_numpy(orders)
    parts, share = [], 0.0
    for direction in (o, o.flip(1)):
        s, share = walk_states(env, direction, k)
        parts.append(s)
    return parts, share


def build_samples(cfg: ImitationConfig, labels: dict[Entry, np.ndarray], k: int,
                  pool: Any = None) -> tuple[Samples, dict[str, float]]:
    """Every state of every label tour in both directions (in ``pool`` when given, the same
    states in the same order); the in-view share per K (``K20t`` for a tiled set)."""
    tasks = [(cfg, e, lo, orders[lo:lo + 500], k)
             for e, orders in labels.items() for lo in range(0, parse_entry(e)[1], 500)]
    mapper: Callable[..., Any] = pool.map if pool is not None else lambda f, t: list(map(f, t))
    parts, coverage = [], {}
    for task, (chunk, share) in zip(tasks, mapper(_chunk_states, tasks), strict=True):
        parts.extend(chunk)
        kk, _, _, tiled = parse_entry(task[1])
        coverage[f"{kk}t" if tiled else str(kk)] = share
    return Samples.join(parts), coverage


def random_maps(n: int, generator: torch.Generator) -> torch.Tensor:
    """``(n, 2, 2)`` random rotations, half of them mirrored."""
    a = torch.rand(n, generator=generator) * 2 * math.pi
    c, s = torch.cos(a), torch.sin(a)
    rot = torch.stack([torch.stack([c, -s], -1), torch.stack([s, c], -1)], -2)
    flip = torch.where(torch.rand(n, generator=generator) < 0.5, -1.0, 1.0)
    rot[:, :, 0] = rot[:, :, 0] * flip[:, None]
    return rot


def imitation_loss(model: LocalPolicy, batch: Samples, maps: torch.Tensor,
                   ) -> tuple[torch.Tensor, torch.Tensor]:
    """Cross-entropy of the target candidates, and the share the model ranks first (a 0-d
    tensor: reading it would wait for a GPU)."""
    logits = model.scores(*turn((batch.cand_vec, batch.cand_sc, batch.ctx_vec, batch.ctx_sc), maps),
                          batch.mask)
    loss = nn.functional.cross_entropy(logits, batch.target)
    acc = (logits.argmax(-1) == batch.target).float().mean().detach()
    return loss, acc


def greedy_gap(model: LocalPolicy, env: EnvBatch, ref: torch.Tensor,
               base: torch.Tensor | float = 0.0) -> float:
    """Mean gap (%) of one-start greedy decoding with optimal heads to ``ref``, both less
    ``base`` (a cost no tour avoids: a tiled set's hover energies, so that its gap is the
    distance's)."""
    model.eval()
    with torch.inference_mode():
        order, _ = model.decode(env, starts=1)
        cost = optimal_heads_batch(env, order)[1]
    model.train()
    return float((((cost - base) / (ref - base) - 1) * 100).mean())


# ---------------------------------------------------------------------- run
def output_paths(ckpt: str | Path) -> dict[str, Path]:
    """The files of a run, from the policy file's path."""
    p = Path(ckpt)
    stem = p.with_suffix("")
    return {"policy": p, "meta": stem.with_suffix(".json"), "log": Path(f"{stem}.imitation.csv"),
            "labels": Path(f"{stem}.labels.npz")}


def _write_log(path: Path, rows: list[dict[str, Any]]) -> None:
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=LOG_COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(path, out.getvalue())


def train(cfg: ImitationConfig, output: str | Path, *, labels: str | Path | None = None,
          progress: bool = True, device: str = "cpu", workers: int = 1,
          labels_only: bool = False) -> dict[str, Any]:
    """Run ``cfg`` (labels, states, training) on ``device``, labels and states in ``workers``
    processes; returns the JSON metadata written beside it (nothing with ``labels_only``: the
    labels are solved into the cache and the run stops)."""
    def say(text: str) -> None:
        if progress:
            print(text, file=sys.stderr, flush=True)

    dev = torch.device(device)
    torch.set_num_threads(cfg.threads)
    torch.manual_seed(cfg.seed)
    paths = output_paths(output)
    cache = Path(labels) if labels else paths["labels"]
    start = time.perf_counter()
    label_orders, refs, label_s = load_or_solve_labels(cfg, cache, say, workers)
    if labels_only:
        say(f"labels in {cache}: {label_s:.0f} s")
        return {}
    model = LocalPolicy(**cfg.model_options)
    pool = fork_pool(workers)
    try:
        data, coverage = build_samples(cfg, label_orders, model.k, pool)
    finally:
        if pool is not None:
            pool.close()
            pool.join()
    say(f"{len(data)} states; next cluster in view: {coverage}")
    vsets = []
    for e in cfg.val:
        vinsts, vomegas = validation_set(e, cfg.nodes)
        venv = env_from_instances(vinsts, vomegas)
        # at omega 0 a node's cost is its cluster's hover energy: the same for every tour
        vbase = venv.node_cost.min(-1).values.sum(-1) if parse_entry(e)[3] else 0.0
        vsets.append((venv, torch.from_numpy(refs[e]), vbase))
    prep_s = time.perf_counter() - start
    gen = torch.Generator().manual_seed(cfg.seed)
    model.to(dev)
    data = Samples(*(getattr(data, f.name).to(dev) for f in dataclasses.fields(Samples)))
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    averaged = (torch.optim.swa_utils.AveragedModel(
        model, multi_avg_fn=torch.optim.swa_utils.get_ema_multi_avg_fn(cfg.ema), use_buffers=True)
        if cfg.ema else None)
    rows: list[dict[str, Any]] = []
    best, best_step = math.inf, 0
    t0 = time.perf_counter()
    window: list[tuple[torch.Tensor, torch.Tensor]] = []
    step = 0
    model.train()
    meta: dict[str, Any] = {}

    def validate() -> float:
        nonlocal best, best_step
        cpu = LocalPolicy(**cfg.model_options)
        weights = (averaged.module if averaged is not None else model).state_dict()
        cpu.load_state_dict({k: v.cpu() for k, v in weights.items()})
        gap = float(np.mean([greedy_gap(cpu, venv, ref, base) for venv, ref, base in vsets]))
        if gap < best:
            best, best_step = gap, step
            save_policy(cpu, paths["policy"])
        return gap

    def write_meta() -> None:
        nonlocal meta
        meta = _meta(cfg, paths, step, best, best_step, label_s, prep_s, time.perf_counter() - t0,
                     coverage, len(data), device, workers)
        atomic_write_text(paths["meta"], json.dumps(meta, indent=2) + "\n")

    while step < cfg.steps:
        wall = time.perf_counter() - t0
        if wall >= cfg.max_time:
            break
        lr = cfg.lr * (0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * wall / cfg.max_time)))
        for g in opt.param_groups:
            g["lr"] = lr
        idx = torch.randint(len(data), (cfg.batch,), generator=gen).to(dev)
        loss, acc = imitation_loss(model, data.take(idx), random_maps(cfg.batch, gen).to(dev))
        opt.zero_grad(set_to_none=True)
        loss.backward()
        nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()
        if averaged is not None:
            averaged.update_parameters(model)
        step += 1
        window.append((loss.detach(), acc))
        if step % cfg.log_every == 0:
            row: dict[str, Any] = {
                "step": step, "loss": float(torch.stack([w[0] for w in window]).mean()),
                "accuracy": float(torch.stack([w[1] for w in window]).mean()), "lr": lr,
                "val_gap_pct": "", "wall_s": round(time.perf_counter() - t0, 1)}
            window = []
            if step % cfg.val_every == 0:
                gap = validate()
                row["val_gap_pct"] = gap
                say(f"step {step}: loss {row['loss']:.4f} acc {row['accuracy']:.3f} "
                    f"val gap {gap:.2f} % (best {best:.2f} % at {best_step})")
            rows.append(row)
            _write_log(paths["log"], rows)
            write_meta()
    gap = validate()
    rows.append({"step": step, "loss": "", "accuracy": "", "lr": "", "val_gap_pct": gap,
                 "wall_s": round(time.perf_counter() - t0, 1)})
    _write_log(paths["log"], rows)
    write_meta()
    return meta


def _meta(cfg: ImitationConfig, paths: dict[str, Path], step: int, best: float, best_step: int,
          label_s: float, prep_s: float, train_s: float, coverage: dict[str, float],
          n_states: int, device: str = "cpu", workers: int = 1) -> dict[str, Any]:
    val_tiled = [parse_entry(e)[3] for e in cfg.val]
    return {
        "model": "local",
        "command": cfg.command(paths["policy"], device, workers),
        "device": torch.cuda.get_device_name() if device.startswith("cuda") else "cpu",
        "seed": cfg.seed,
        "steps": best_step,
        "steps_trained": step,
        "label_wall_s": round(label_s, 1),
        "prep_wall_s": round(prep_s, 1),
        "wall_s": round(train_s, 1),
        "val_gap_pct": best,
        "validation": {"seed": VAL_SEED, "sets": [list(e) for e in cfg.val],
                       "tiled": all(val_tiled),
                       "omega": ([0.0] if all(val_tiled) else [0.0, 0.3, 0.6] if any(val_tiled)
                                 else [0.3, 0.6]),
                       "gap": "mean over the sets of each set's mean gap",
                       "reference": "lns stop_at_convergence",
                       "decoding": "greedy, one start, optimal heads"},
        "states": n_states,
        "next_in_view": coverage,
        "config": LocalPolicy(**cfg.model_options).config,
        "train": dataclasses.asdict(cfg),
        "torch": torch.__version__,
    }


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m gtsp_bench.solvers.learned.imitation``: train the local-view policy."""
    p = OneLineParser(prog="python -m gtsp_bench.solvers.learned.imitation",
                                description="train the local-view policy by imitating lns tours")
    p.add_argument("--recipe", default="local", help=f"one of {', '.join(RECIPES)} (default: local)")
    p.add_argument("--max-time", type=arg_float, default=None,
                   help="training seconds (default: the recipe's)")
    p.add_argument("--seed", type=arg_seed, default=None, help="seed of the weights and batches")
    p.add_argument("--labels", default=None, help="label cache (default: CKPT.labels.npz)")
    p.add_argument("--device", default="cpu", help="torch device of the training (default: cpu)")
    p.add_argument("--workers", type=int, default=1,
                   help="processes for the labels and states (default: 1)")
    p.add_argument("--labels-only", action="store_true",
                   help="solve the labels into the cache and stop")
    p.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")
    p.add_argument("-o", "--output", required=True, help="policy file to write")
    args = p.parse_args(argv)
    try:
        over: dict[str, Any] = {}
        if args.max_time is not None:
            over["max_time"] = args.max_time
        if args.seed is not None:
            over["seed"] = args.seed
        cfg = get_recipe(args.recipe, **over)
        if args.workers < 1:
            raise InputError(f"--workers must be at least 1, got {args.workers}")
        try:
            dev = torch.device(args.device)
        except (RuntimeError, ValueError) as e:
            raise InputError(f"bad device {args.device!r}: {str(e).splitlines()[0]}") from None
        if dev.type not in ("cpu", "cuda") or (dev.type == "cuda" and not torch.cuda.is_available()):
            raise InputError(f"device {args.device!r} is not usable here (valid: cpu, cuda)")
        meta = train(cfg, args.output, labels=args.labels, progress=not args.no_progress,
                     device=args.device, workers=args.workers, labels_only=args.labels_only)
        if args.labels_only:
            return 0
    except InputError as e:
        print(f"gtsp-bench: error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {args.output}: step {meta['steps']} of {meta['steps_trained']}, "
          f"validation gap {meta['val_gap_pct']:.2f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
