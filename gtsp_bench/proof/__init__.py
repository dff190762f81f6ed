"""Proof certificates of optimality, and their independent checker.

A certificate (written by the ``milp`` solver, ``certificate=PATH``) holds the incumbent tour and a
branch-and-bound tree over the GTSP's binary model (``y_i``: node ``i`` is its cluster's head;
``x_ij``: the tour uses edge ``{i, j}`` between two clusters). Every leaf carries LP dual values
over rows that the checker rebuilds itself: the cluster and degree equalities and cuts, each named
by its family and defining sets (:mod:`gtsp_bench.proof.families`). :func:`check_certificate`
re-derives every bound from those duals in exact integer arithmetic (no LP solver), checks each
cut by its family, checks that the leaves cover the whole space and re-prices the tour with the
shared evaluator.

Modules, each importing only the ones above it:

* :mod:`~gtsp_bench.proof.format`: the versioned JSON layout, reading and writing (gzip), the
  instance fingerprint, variables;
* :mod:`~gtsp_bench.proof.encode`: version 2's dense layout of cuts and proofs, and the
  conversions between the versions;
* :mod:`~gtsp_bench.proof.families`: the cut families, their validity and coefficients;
* :mod:`~gtsp_bench.proof.bounds`: the exact Lagrangian and Farkas bounds of a dual vector over a
  domain of fixed variables;
* :mod:`~gtsp_bench.proof.check`: the tree walk (:class:`~gtsp_bench.proof.check.ProofChecker`)
  and :func:`check_certificate`;
* :mod:`~gtsp_bench.proof.trim` and :mod:`~gtsp_bench.proof.compact`: shorter certificates
  (fewer root fixings; each proof on the coarsest scale that still checks), for the writer.

The package imports nothing from the solvers: a certificate is checked without the code that
wrote it.
"""

from gtsp_bench.proof.check import CheckResult, ProofError, check_certificate

__all__ = ["CheckResult", "ProofError", "check_certificate"]
