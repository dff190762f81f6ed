"""Shared fixtures: tiny hand-checkable instances and the GTSPLIB samples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gtsp_bench.instance import Instance

REPO = Path(__file__).resolve().parents[1]
#: The GTSPLIB library, a folder of the repository (instances/gtsplib/README.md).
GTSPLIB = REPO / "instances" / "gtsplib"
#: The optional extras' solvers and the package each needs (their tests run where it is installed).
OPTIONAL_PACKAGE = {"gurobi": "gurobipy", "lkh": "elkai", "pyvrp": "pyvrp"}


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
    """The five sample instances the tests use (:data:`gtsp_bench.data.gtsplib.SAMPLES`)."""
    from gtsp_bench.data.gtsplib import SAMPLES

    return [GTSPLIB / f"{name}.gtsp.gz" for name in SAMPLES]


def uncompacted(instance: Instance, cert: dict, trim: bool = True, strict: bool = False) -> dict:
    """A stand-in for ``compact_certificate`` that leaves a certificate as the writer made it
    before version 2 (still checked when ``strict``, so that the writer's fallbacks run)."""
    from gtsp_bench.proof import check_certificate

    if strict:
        check_certificate(instance, cert)
    return cert
