"""An example third-party gtsp-bench solver, registered through the ``gtsp_bench.solvers`` entry point."""

from __future__ import annotations

import numpy as np

from gtsp_bench import Instance, Solution, evaluate


class NearestCenter:
    """Each cluster's most central node; clusters visited by angle around the depot."""

    def solve(self, instance: Instance, omega: float | None, *, time_limit: float | None,
              seed: int) -> Solution:
        """Heads: the node nearest each cluster's centroid; order: their angle around the depot
        (around the centroid of all nodes when there is no depot)."""
        heads = [int(np.argmin(((pts - pts.mean(axis=0)) ** 2).sum(axis=1))) for pts in instance.clusters]
        hub = instance.depot if instance.depot is not None else instance.coords.mean(axis=0)
        chosen = np.array([pts[h] for pts, h in zip(instance.clusters, heads, strict=True)])
        angles = np.arctan2(chosen[:, 1] - hub[1], chosen[:, 0] - hub[0])
        order = [int(k) for k in np.argsort(angles, kind="stable")]
        return Solution(tuple(order), tuple(heads), evaluate(instance, omega, order, heads).objective)
