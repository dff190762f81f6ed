"""Policy files: save and load a policy (config + weights), and the shipped models' folder.

A policy file is a ``torch.save`` of ``{"kind", "config", "state_dict"}``, loaded with
``weights_only=True`` (tensors and plain data only, never pickled code). The shipped models are
``checkpoints/<model>.pt`` beside this module, each with the JSON record and training log its
run wrote; the runner keys learned solves by a hash of those weight files
(:func:`checkpoint_revision`).
"""

from __future__ import annotations

import hashlib
import io
from pathlib import Path

import torch
from gtsp_bench.solvers.learned import CHECKPOINT_DIR
from gtsp_bench.solvers.learned.policies import build_policy
from torch import nn

from gtsp_bench.data.io import atomic_write_bytes
from gtsp_bench.errors import InputError

#: Where the shipped checkpoints live.
#: Marker of a policy file.
FILE_KIND = "gtsp-bench-policy"


def shipped_checkpoint(model: str) -> Path:
    """The shipped policy file of ``model`` (``checkpoints/<model>.pt``; it may be missing)."""
    return CHECKPOINT_DIR / f"{model}.pt"


def checkpoint_revision(path: str | Path) -> str:
    """The first 12 hex digits of the file's SHA-256, or ``"missing"`` without a file."""
    p = Path(path)
    if not p.is_file():
        return "missing"
    return hashlib.sha256(p.read_bytes()).hexdigest()[:12]


def save_policy(model: nn.Module, path: str | Path) -> None:
    """Write a policy file (config + state_dict) atomically."""
    buf = io.BytesIO()
    torch.save({"kind": FILE_KIND, "config": model.config, "state_dict": model.state_dict()}, buf)
    atomic_write_bytes(path, buf.getvalue())


def load_policy(path: str | Path, model_name: str | None = None) -> nn.Module:
    """Load a policy file written by :func:`save_policy` (weights only, never pickled code).

    Raises
    ------
    InputError
        One line naming the file: missing, unreadable or corrupt, not a policy, a different
        model than ``model_name``, or weights whose shapes do not fit the config.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such checkpoint file")
    try:
        data = torch.load(p, map_location="cpu", weights_only=True)
    except Exception:  # torch raises many kinds (and long texts) on a corrupt or foreign file
        raise InputError(
            f"{p}: not a readable checkpoint (not a file written by 'gtsp-bench train', or damaged)"
        ) from None
    if not isinstance(data, dict) or data.get("kind") != FILE_KIND:
        raise InputError(f"{p}: not a gtsp-bench policy checkpoint")
    config = data.get("config")
    if not isinstance(config, dict):
        raise InputError(f"{p}: checkpoint has no model config")
    if model_name is not None and config.get("model") != model_name:
        raise InputError(f"{p}: checkpoint holds a {config.get('model')!r} model, not {model_name!r}")
    try:
        model = build_policy(config)
    except InputError as e:
        raise InputError(f"{p}: {e}") from None
    try:
        model.load_state_dict(data["state_dict"])
    except (RuntimeError, KeyError, TypeError) as e:
        first = str(e).strip().splitlines()
        reason = " ".join(line.strip() for line in first[:2])[:160]
        raise InputError(f"{p}: weights do not fit the model config ({reason})") from None
    model.eval()
    return model
