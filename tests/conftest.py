"""Shared fixtures: tiny hand-checkable instances and the GTSPLIB samples."""

from __future__ import annotations

import inspect
import os
from pathlib import Path

import numpy as np
import pytest

from gtsp_bench.instance import Instance

REPO = Path(__file__).resolve().parents[1]
#: GTSPLIB samples live beside the project, not in it (see ../shared/gtsplib/README.md);
#: GTSP_BENCH_GTSPLIB points elsewhere.
GTSPLIB = Path(os.environ.get("GTSP_BENCH_GTSPLIB", REPO.parent / "shared" / "gtsplib"))
DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture
def tiny() -> Instance:
    """Depot at the origin; cluster 0 has one node, cluster 1 two nodes.

    With omega = 0 the best tour is depot -> (0, 300) -> (300, 0) -> depot, 1024.26 m long.
    """
    return Instance(
        name="tiny",
        clusters=(np.array([[0.0, 300.0]]), np.array([[400.0, 300.0], [300.0, 0.0]])),
        depot=np.array([0.0, 0.0]),
    )


@pytest.fixture(autouse=True)
def _restore_solver_registry():
    """Solvers a test registers are gone after it, so that they do not join later tests' default
    benchmark runs (the runner uses every registered solver)."""
    from gtsp_bench import registry

    saved = dict(registry._registry())
    yield
    registry._REGISTRY.clear()
    registry._REGISTRY.update(saved)


def gtsplib_files() -> list[Path]:
    """All sample .gtsp files (an empty list if the shared folder is missing)."""
    return sorted(GTSPLIB.glob("*.gtsp"))


def pytest_collection_modifyitems(config, items):
    """Skip, with the reason shown, tests that read GTSPLIB files when the folder is missing."""
    if GTSPLIB.is_dir():
        return
    skip = pytest.mark.skip(reason=f"GTSPLIB samples not found at {GTSPLIB}")
    for item in items:
        func = getattr(item, "function", None)
        if func is not None and "GTSPLIB" in inspect.getsource(func):
            item.add_marker(skip)
