"""The certificate file: a versioned JSON object, gzip-compressed (``.cert.json.gz``).

Layout of version 1 (docs/proofs.md documents both versions for outsiders; version 2, which
:data:`VERSION` names and the solver writes, holds the same fields with cuts and proofs written
more densely, :mod:`gtsp_bench.proof.encode`, and the checker reads both):

* ``format`` (:data:`FORMAT`), ``version``;
* ``instance``: ``name``, ``nodes``, ``clusters`` and ``costs_sha256`` (:func:`fingerprint`), and
  ``omega`` (``null`` for a GTSPLIB file);
* ``tour``: node ids of the incumbent (the priced problem's ids: for a UAV instance the depot is
  the last node), ``value``: its cost;
* ``cutoff``: a number ``T``; the certificate claims that every tour costs more than ``T``
  (integer costs: ``T = value - 1`` proves ``value`` optimal);
* ``dual_bits``: every dual value is an integer ``k`` standing for ``k / 2**dual_bits``;
* ``cuts``: the cut rows, each ``{"family": ..., ...sets}`` (:mod:`gtsp_bench.proof.families`);
* ``proofs``: dual vectors ``{"kind": "dual" | "farkas", "cluster": [[c, k], ...],
  "degree": [[i, k], ...], "cuts": [[row, k], ...]}`` (sparse; absent entries are 0);
* ``nodes``: the tree, root first: ``{"parent": p, "branch": [var, value]}`` (the root has
  neither), an optional ``fix`` list applied in order (``{"proof": k, "rule": "reduced_cost"}``:
  every free variable whose fixing to 1 the proof bounds above ``T`` is fixed to 0;
  ``{"proof": k, "vars": [[var, value], ...]}``: each variable fixed to ``value``, the proof
  bounding the node with it at ``1 - value`` above ``T``), and, at a leaf, ``proof``: the index of
  the proof that bounds it above ``T``.

A variable is ``["y", i]`` (node ``i`` heads its cluster) or ``["x", i, j]`` (edge ``{i, j}``,
``i < j``, between two clusters).
"""

from __future__ import annotations

import gzip
import hashlib
import json
import os
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from gtsp_bench.checks import is_int
from gtsp_bench.errors import InputError
from gtsp_bench.problem import Problem

#: The ``format`` field of every certificate.
FORMAT = "gtsp-bench proof certificate"
#: The version this package writes.
VERSION = 2
#: The versions the checker reads (version 1: every dual sparse, sets as plain lists).
READABLE = (1, 2)
#: Suffix of a certificate file.
SUFFIX = ".cert.json.gz"


def fingerprint(problem: Problem) -> str:
    """SHA-256 of the priced problem's clusters, node costs and edge costs (their float64 bytes):
    a certificate names the exact costs it proves optimality for."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(problem.cluster_of, dtype=np.int64).tobytes())
    h.update(np.ascontiguousarray(problem.node_cost, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(problem.edge_cost, dtype=np.float64).tobytes())
    return h.hexdigest()


def instance_header(problem: Problem) -> dict[str, Any]:
    """The ``instance`` object of a certificate for ``problem``."""
    return {"name": problem.instance.name, "nodes": problem.n_nodes, "clusters": problem.n_clusters,
            "costs_sha256": fingerprint(problem), "omega": problem.omega}


def write_certificate(path: str | os.PathLike[str], cert: dict[str, Any]) -> int:
    """Write ``cert`` as gzip-compressed JSON, atomically (a temporary file, then a rename);
    returns the bytes written."""
    path = Path(path)
    data = gzip.compress(json.dumps(cert, separators=(",", ":")).encode(), compresslevel=9, mtime=0)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)
    return len(data)


def read_certificate(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a certificate (gzip-compressed or plain JSON).

    Raises
    ------
    InputError
        ``"<path>: <problem>"``: missing or unreadable, not JSON, not a certificate, or another
        version.
    """
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e.strerror or e})") from None
    try:
        if data[:2] == b"\x1f\x8b":
            data = gzip.decompress(data)
        cert = json.loads(data)
    except (gzip.BadGzipFile, EOFError, zlib.error, UnicodeDecodeError, ValueError) as e:
        raise InputError(f"{path}: not a certificate (not gzip-compressed JSON: {e})") from None
    if not isinstance(cert, dict) or cert.get("format") != FORMAT:
        raise InputError(f"{path}: not a certificate (no 'format': {FORMAT!r})")
    if cert.get("version") not in READABLE:
        raise InputError(f"{path}: certificate version {cert.get('version')!r}; this checker reads "
                         f"versions {', '.join(map(str, READABLE))}")
    return cert


def parse_var(var: Any, n_nodes: int, cluster_of: np.ndarray) -> tuple[int, int]:
    """``(i, j)`` of a variable: ``(i, -1)`` for ``["y", i]``, ``(i, j)`` for ``["x", i, j]``.

    Raises
    ------
    ValueError
        For anything else (unknown node, ``i >= j``, an edge inside one cluster).
    """
    ok = isinstance(var, list) and all(is_int(v) for v in var[1:])
    if ok and len(var) == 2 and var[0] == "y" and 0 <= var[1] < n_nodes:
        return int(var[1]), -1
    if (ok and len(var) == 3 and var[0] == "x" and 0 <= var[1] < var[2] < n_nodes
            and cluster_of[var[1]] != cluster_of[var[2]]):
        return int(var[1]), int(var[2])
    raise ValueError(f"{var!r} is not a variable (['y', i] or ['x', i, j] with i < j in two clusters)")


def var_name(i: int, j: int) -> str:
    """``y[i]`` or ``x[i,j]``."""
    return f"y[{i}]" if j < 0 else f"x[{i},{j}]"
