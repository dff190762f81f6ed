"""The proof log of a branch and cut, written as a certificate that :mod:`gtsp_bench.proof` checks.

:class:`ProofLog` records, while the search runs, the dual vector of every LP that proves
something (the root's best bound, each reduced-cost fixing round, each leaf, each child shown
empty by strong branching) together with its cuts of nonzero dual (each cut's row kept once), and
the tree (which variable each node branched on). :meth:`ProofLog.certificate` turns it into the format of
:mod:`gtsp_bench.proof.format`: each LP cut row becomes a member of a named family
(:mod:`gtsp_bench.proof.families`) with its defining sets. The LP holds a cut in a form shifted by
equalities (a side written over its crossing edges adds degree rows; a right-hand side of ``-1``
or ``|W| - 1`` adds cluster rows), so the row's dual moves onto those equalities, which leaves
the dual function unchanged. Duals are rounded to multiples of ``2**-DUAL_BITS``; any dual of the
right signs gives a valid bound, and the checker re-derives it exactly.

The search must run without pruning of candidate heads (a certificate covers every node) and
without LP cutoffs (a cut-off LP has no dual to prove its bound); :func:`solve_exact` sees to that.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gtsp_bench.solvers.exact.mip.model import GtspModel
from gtsp_bench.solvers.exact.mip.separation import Cuts

from gtsp_bench.proof.check import ProofError
from gtsp_bench.proof.compact import compact_certificate
from gtsp_bench.proof.format import FORMAT, instance_header

#: Duals are written as integers over ``2**DUAL_BITS``.
DUAL_BITS = 32


class CertificateError(RuntimeError):
    """The search's log cannot be written as a certificate (a bug, not bad input)."""


@dataclass(frozen=True)
class RawProof:
    """One LP's row duals (or Farkas ray), over its cuts of nonzero dual only.

    Attributes
    ----------
    kind
        ``"dual"`` or ``"farkas"``.
    duals
        The cluster rows', the degree rows', then those cuts' duals.
    ids
        The log's id of each of those cuts (their rows are kept once in :attr:`ProofLog.cut_rows`).
    """

    kind: str
    duals: np.ndarray
    ids: np.ndarray


@dataclass
class _Node:
    parent: int | None
    branch: tuple[int, int] | None  # (model column, value)
    fix: list[dict[str, Any]] = field(default_factory=list)
    proof: int | None = None
    lp: int | None = None  # the proof of the bound it branched with (closes children not solved)


class ProofLog:
    """The search's proofs and tree, in model columns.

    Parameters
    ----------
    model
        The model (every node a candidate head: no pruning).
    """

    def __init__(self, model: GtspModel) -> None:
        self.model = model
        self.proofs: list[RawProof] = []
        #: Each cut a proof uses, by id, as a one-row block: kept once, however many proofs use
        #: it (a proof holding the LP's whole cut block took 18 GB over a 3,600 s search of
        #: 200E1k.0, and more at 207si1032).
        self.cut_rows: dict[int, Cuts] = {}
        self.nodes: list[_Node] = [_Node(None, None)]
        self.best_root: tuple[float, int] | None = None
        self.root_fixed: list[np.ndarray] = []  # the columns each root fixing fixed
        self.lock = threading.RLock()  # the branch and cut's workers record at once

    # -------------------------------------------------------------- recording
    def proof(self, kind: str, duals: np.ndarray, cuts: Cuts, ids: np.ndarray) -> int:
        """Record one LP's duals (or Farkas ray) over its base rows and ``cuts`` (ids ``ids``);
        its index. A cut of zero dual adds nothing to the proof and is not kept."""
        with self.lock:
            base = self.model.n_clusters + self.model.n_nodes
            duals = np.asarray(duals, dtype=float)
            used = np.flatnonzero(duals[base:] != 0)
            new = [r for r in used if int(ids[r]) not in self.cut_rows]
            if new:
                mask = np.zeros(len(cuts), dtype=bool)
                mask[new] = True
                block = cuts.select(mask)
                for j, r in enumerate(new):
                    self.cut_rows[int(ids[r])] = block.select(np.arange(len(block)) == j)
            self.proofs.append(RawProof(kind, np.concatenate([duals[:base], duals[base:][used]]),
                                        np.asarray(ids)[used].copy()))
            return len(self.proofs) - 1

    def _cuts(self, proof: RawProof) -> Cuts:
        """The cuts of ``proof``'s duals, in their order."""
        if not len(proof.ids):
            return Cuts.empty(self.model.n_nodes)
        return Cuts.stack([self.cut_rows[int(i)] for i in proof.ids])

    def root_round(self, bound: float, proof: int, fixed: np.ndarray | None = None) -> None:
        """A root LP round: its bound (kept if the best) and the model columns it fixed, if any."""
        with self.lock:
            if self.best_root is None or bound > self.best_root[0]:
                self.best_root = (bound, proof)
            if fixed is not None:
                self.nodes[0].fix.append({"proof": proof, "rule": "reduced_cost"})
                self.root_fixed.append(fixed)

    def fix_rule(self, node: int, proof: int) -> None:
        """Reduced-cost fixing at ``node`` with ``proof``."""
        with self.lock:
            self.nodes[node].fix.append({"proof": proof, "rule": "reduced_cost"})
            self.nodes[node].lp = proof

    def fix_var(self, node: int, proof: int, col: int, value: int) -> None:
        """Model column ``col`` fixed to ``value`` at ``node``, ``proof`` closing the other side."""
        with self.lock:
            self.nodes[node].fix.append({"proof": proof, "vars": [(col, value)]})

    def leaf(self, node: int, proof: int) -> None:
        """``node`` closed by ``proof``."""
        with self.lock:
            self.nodes[node].proof = proof

    def child(self, parent: int, col: int, value: int) -> int:
        """A new child of ``parent`` with model column ``col`` at ``value``; its id."""
        with self.lock:
            self.nodes.append(_Node(parent, (col, value)))
            return len(self.nodes) - 1

    def close_unsolved(self, node: int) -> None:
        """``node`` was never solved (its parent's bound already closes it)."""
        with self.lock:
            parent = self.nodes[node].parent
            lp = None if parent is None else self.nodes[parent].lp
            if lp is None:
                raise CertificateError(f"node {node}: closed by its parent's bound, which has no proof")
            self.nodes[node].proof = lp

    # -------------------------------------------------------------- writing
    def _var(self, col: int) -> list[Any]:
        model, n = self.model, self.model.n_nodes
        if col < n:
            return ["y", int(model.nodes[col])]
        a, b = int(model.nodes[model.tail[col - n]]), int(model.nodes[model.head[col - n]])
        return ["x", min(a, b), max(a, b)]

    def _family(self, cuts: Cuts, r: int) -> tuple[dict[str, Any], dict[int, float], list[np.ndarray]]:
        """Row ``r`` of ``cuts`` as a family member, the cluster rows added to its canonical form
        (cluster -> multiple), and the sides written over crossing edges (each adds -1/2 of its
        nodes' degree rows)."""
        model = self.model
        sides = np.flatnonzero(cuts.row == r)
        crossing = [cuts.side[s] for s in sides if cuts.cross[s]]
        a = cuts.ycoef[r] - sum((c.astype(float) for c in crossing), np.zeros(model.n_nodes))
        a, rhs = np.round(a).astype(np.int64), float(cuts.rhs[r])
        if len(sides) > 1:
            return self._blossom(cuts.side[sides], a, rhs), {}, crossing
        gsec, alpha = gsec_form(model.cluster, cuts.side[sides[0]], a, rhs)
        gsec["Q"] = [int(v) for v in model.nodes[cuts.side[sides[0]]]]
        return gsec, alpha, crossing

    def _blossom(self, sides: np.ndarray, a: np.ndarray, rhs: float) -> dict[str, Any]:
        cl = self.model.cluster
        handle = np.unique(cl[sides[0]])
        teeth = []
        for s in sides[1:]:
            pair = np.unique(cl[s])
            inner = [int(c) for c in pair if c in handle]
            outer = [int(c) for c in pair if c not in handle]
            if len(inner) != 1 or len(outer) != 1:
                raise CertificateError("a blossom tooth is not one cluster pair across the handle")
            teeth.append([inner[0], outer[0]])
        if (a != 0).any() or rhs != len(handle) + (len(teeth) - 1) / 2:
            raise CertificateError("a multi-sided row is not a blossom")
        for s, want in zip(sides, [handle] + [np.array(t) for t in teeth], strict=True):
            if not np.array_equal(s, np.isin(cl, want)):
                raise CertificateError("a blossom side is not a union of whole clusters")
        return {"family": "blossom", "handle": [int(c) for c in handle], "teeth": teeth}

    def certificate(self, problem: Any, tour: np.ndarray, value: float, cutoff: float,
                    open_nodes: list[int]) -> dict[str, Any]:
        """The certificate of this log.

        Parameters
        ----------
        problem
            The priced problem.
        tour
            The incumbent (problem node ids).
        value
            Its cost.
        cutoff
            The claimed bound: every tour costs more.
        open_nodes
            Nodes left unsolved because their parent's bound closes them.
        """
        if len(self.nodes) == 1 and self.nodes[0].proof is None:  # the root proved it
            if self.best_root is None:
                raise CertificateError("the root has no proof")
            self.nodes[0].proof = self.best_root[1]
        for k in open_nodes:
            self.close_unsolved(k)
        full = self.nodes[0].fix
        for chained in ((False, True) if len(full) > 1 else ()):
            self.nodes[0].fix = self._needed_fixings(chained)
            cert = self._write(problem, tour, value, cutoff)
            try:  # fewer fixings are a shorter proof only if it still holds
                return compact_certificate(problem.instance, cert, trim=False, strict=True)
            except ProofError:
                self.nodes[0].fix = full
        return compact_certificate(problem.instance, self._write(problem, tour, value, cutoff), trim=False)

    def _needed_fixings(self, chained: bool) -> list[dict[str, Any]]:
        """The root fixings that fixed a column whose reduced cost is not clearly positive at a
        proof that relies on them (a leaf's, a later fixing's and, if ``chained``, a needed root
        fixing's own): a column of positive reduced cost leaves a bound as it is when free."""
        model = self.model
        fixes = self.nodes[0].fix
        cols = np.unique(np.concatenate(self.root_fixed))
        small = 1e-6 * max(1.0, float(np.abs(model.cost).max()))
        own = {f["proof"] for f in fixes}
        todo = {nd.proof for nd in self.nodes if nd.proof is not None}
        todo |= {f["proof"] for nd in self.nodes[1:] for f in nd.fix} | (todo & own)
        done: set[int] = set()
        keep = np.zeros(len(fixes), dtype=bool)
        while todo:
            k = todo.pop()
            done.add(k)
            needed = np.zeros(model.n_cols, dtype=bool)
            needed[cols[self._reduced_costs(self.proofs[k], cols) < small]] = True
            for i, fixed in enumerate(self.root_fixed):
                if not keep[i] and needed[fixed].any():
                    keep[i] = True
                    if chained and fixes[i]["proof"] not in done:
                        todo.add(fixes[i]["proof"])
        return [f for f, kept in zip(fixes, keep, strict=True) if kept]

    def _reduced_costs(self, proof: RawProof, cols: np.ndarray) -> np.ndarray:
        """Reduced costs of model columns ``cols`` at a logged LP's duals."""
        model, n, m = self.model, self.model.n_nodes, self.model.n_clusters
        u, pi, mu = proof.duals[:m], proof.duals[m:m + n], proof.duals[m + n:]
        is_y = cols < n
        ys, es = cols[is_y], cols[~is_y] - n
        on_edge, on_y = self._cuts(proof).dual_weights(model, mu, es)
        rc = np.empty(len(cols))
        rc[is_y] = model.cost[ys] - u[model.cluster[ys]] + 2 * pi[ys] - on_y[ys]
        rc[~is_y] = model.cost[n + es] - pi[model.tail[es]] - pi[model.head[es]] - on_edge
        return rc

    def _write(self, problem: Any, tour: np.ndarray, value: float, cutoff: float) -> dict[str, Any]:
        """The certificate of the log as it stands."""
        used = sorted({f["proof"] for nd in self.nodes for f in nd.fix}
                      | {nd.proof for nd in self.nodes if nd.proof is not None})
        renumber = {old: new for new, old in enumerate(used)}
        cut_index: dict[int, int] = {}
        cuts_out: list[dict[str, Any]] = []
        cache: dict[int, tuple[int, dict[int, float], list[np.ndarray]]] = {}
        proofs_out = [self._proof(self.proofs[k], cut_index, cuts_out, cache) for k in used]
        nodes_out = []
        for nd in self.nodes:
            out: dict[str, Any] = {}
            if nd.parent is not None and nd.branch is not None:
                out["parent"] = nd.parent
                out["branch"] = [self._var(nd.branch[0]), int(nd.branch[1])]
            if nd.fix:
                out["fix"] = [{"proof": renumber[f["proof"]], "rule": f["rule"]} if "rule" in f else
                              {"proof": renumber[f["proof"]],
                               "vars": [[self._var(c), int(v)] for c, v in f["vars"]]} for f in nd.fix]
            if nd.proof is not None:
                out["proof"] = renumber[nd.proof]
            nodes_out.append(out)
        head = instance_header(problem)
        return {"format": FORMAT, "version": 1, "instance": head,
                "tour": [int(v) for v in tour], "value": float(value), "cutoff": float(cutoff),
                "dual_bits": DUAL_BITS, "cuts": cuts_out, "proofs": proofs_out, "nodes": nodes_out}

    def _proof(self, raw: RawProof, cut_index: dict[int, int], cuts_out: list[dict[str, Any]],
               cache: dict[int, tuple[int, dict[int, float], list[np.ndarray]]]) -> dict[str, Any]:
        model = self.model
        n, m = model.n_nodes, model.n_clusters
        u = raw.duals[:m].copy()
        pi = raw.duals[m:m + n].copy()
        mu = np.minimum(raw.duals[m + n:], 0.0)
        scale = 2.0**DUAL_BITS
        cut_entries = []
        for r in np.flatnonzero(np.round(mu * scale) != 0):
            cid = int(raw.ids[r])
            if cid not in cache:
                fam, alpha, crossing = self._family(self.cut_rows[cid], 0)
                cut_index[cid] = len(cuts_out)
                cuts_out.append(fam)
                cache[cid] = (cut_index[cid], alpha, crossing)
            index, alpha, crossing = cache[cid]
            lam = float(mu[r])
            for c, a in alpha.items():
                u[c] += lam * a
            for side in crossing:
                pi[side] -= lam / 2
            cut_entries.append([index, int(np.round(lam * scale))])
        cl = [[int(c), int(v)] for c, v in enumerate(np.round(u * scale)) if v != 0]
        deg = [[int(model.nodes[i]), int(v)] for i, v in enumerate(np.round(pi * scale)) if v != 0]
        return {"kind": raw.kind, "cluster": cl, "degree": sorted(deg), "cuts": cut_entries}


def gsec_form(cluster: np.ndarray, q: np.ndarray, a: np.ndarray, rhs: float
              ) -> tuple[dict[str, Any], dict[int, float]]:
    """The generalized subtour row ``x(E(Q)) + a.y <= rhs`` as ``gsec(Q, C1, C2)`` plus cluster
    rows: clusters ``C1 != C2`` and multiples ``alpha_C`` with ``a = -1[Q - C1] - 1[Q & C2] +
    sum_C alpha_C 1[C]`` and ``rhs = sum_C alpha_C``.

    Parameters
    ----------
    cluster
        Cluster of each (local) node.
    q
        Bool mask of ``Q``.
    a
        Integer y coefficients.
    rhs
        The right-hand side.

    Returns
    -------
    tuple
        ``{"family": "gsec", "C1": c1, "C2": c2}`` (``Q`` to be added) and ``{C: alpha_C}``
        (nonzero ones).

    Raises
    ------
    CertificateError
        When the row is no such combination.
    """
    m = int(cluster.max()) + 1
    vin: dict[int, set[int]] = {}
    vout: dict[int, set[int]] = {}
    for c, inside, coef in zip(cluster, q, a, strict=True):
        (vin if inside else vout).setdefault(int(c), set()).add(int(coef))
    if any(len(v) > 1 for v in (*vin.values(), *vout.values())):
        raise CertificateError("a cut's y coefficients vary inside a cluster side")
    alpha: dict[int, int] = {}
    c1 = c2 = None
    full, disjoint = [], []
    for c in range(m):
        i, o = vin.get(c), vout.get(c)
        if i and o:
            delta = next(iter(i)) - next(iter(o))
            alpha[c] = next(iter(o))
            if delta == 0 and c1 is None:
                c1 = c
            elif delta == -2 and c2 is None:
                c2 = c
            elif delta != -1:
                raise CertificateError("a cut is not a generalized subtour row")
        elif i:
            alpha[c] = next(iter(i)) + 1
            full.append(c)
        else:
            alpha[c] = next(iter(o))
            disjoint.append(c)
    need = round(rhs) - sum(alpha.values())
    ones = [(c1, 0)] if c1 is not None else [(c, -1) for c in full[:2]] + [(c, 0) for c in disjoint[:2]]
    twos = [(c2, 0)] if c2 is not None else [(c, 1) for c in full[:2]] + [(c, 0) for c in disjoint[:2]]
    for (x1, s1) in ones:
        for (x2, s2) in twos:
            if x1 != x2 and s1 + s2 == need:
                alpha[x1] += s1
                alpha[x2] += s2
                form = {"family": "gsec", "C1": int(x1), "C2": int(x2)}
                canon = -((q & (cluster != x1)).astype(np.int64) + (q & (cluster == x2)))
                if not np.array_equal(canon + np.array([alpha[c] for c in cluster]), a) or \
                        sum(alpha.values()) != round(rhs) or rhs != round(rhs):
                    raise CertificateError("a cut's generalized subtour form does not match")
                return form, {c: float(v) for c, v in alpha.items() if v != 0}
    raise CertificateError("a cut is not a generalized subtour row (no clusters C1, C2 fit)")
