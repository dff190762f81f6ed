"""Shared fixtures: tiny hand-checkable instances and the GTSPLIB samples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gtsp_bench.instance import Instance

REPO = Path(__file__).resolve().parents[1]
#: GTSPLIB samples live beside the project, not in it (see ../shared/gtsplib/README.md).
GTSPLIB = REPO.parent / "shared" / "gtsplib"
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


def gtsplib_files() -> list[Path]:
    """All sample .gtsp files (an empty list if the shared folder is missing)."""
    return sorted(GTSPLIB.glob("*.gtsp"))
