"""The checker: walk a certificate's tree and re-derive every bound exactly.

:func:`check_certificate` checks, in this order: that the certificate names this instance's
costs, the incumbent's price (the shared evaluator, :func:`gtsp_bench.energy.evaluate`), every
cut's family and sets, and then the tree from its root: each node's fixings (each proven by a
proof over the other side), each leaf's bound above the cutoff, and that every inner node has the
two children ``v = 0`` and ``v = 1`` of one free variable (so the leaves cover every tour). The
first step that fails raises :class:`ProofError` naming it.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from gtsp_bench.checks import is_int
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InfeasibleSolutionError, InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.proof.bounds import Domain, Priced, Space, price_duals
from gtsp_bench.proof.encode import decode_cut, decode_proofs
from gtsp_bench.proof.families import Cut, parse_cut
from gtsp_bench.proof.format import READABLE, fingerprint, parse_var, var_name

#: Proofs whose reduced costs are kept between uses (a parent's proof closes its children).
_CACHE = 4
#: A float-cost certificate counts as proving optimality when its gap is at most this share of
#: the value (the ``milp`` solver's own tolerance is 1e-6 absolute).
FLOAT_GAP = 1e-6


class ProofError(Exception):
    """A certificate that does not prove what it claims: the message names the first failing step."""


@dataclass(frozen=True)
class CheckResult:
    """What a certificate proves.

    Attributes
    ----------
    value
        The incumbent's cost by the shared evaluator.
    cutoff
        Every tour costs more than this (exact).
    integral
        Whether all costs are integers (then every tour costs at least ``floor(cutoff) + 1``).
    proven
        Whether the incumbent is optimal (integer costs: ``floor(cutoff) + 1 >= value``; float
        costs: a gap of at most :data:`FLOAT_GAP` of the value).
    nodes, leaves
        Size of the tree.
    """

    value: float
    cutoff: Fraction
    integral: bool
    proven: bool
    nodes: int
    leaves: int

    @property
    def lower_bound(self) -> float:
        """The certified lower bound on every tour's cost."""
        return math.floor(self.cutoff) + 1 if self.integral else float(self.cutoff)

    @property
    def gap(self) -> float:
        """The incumbent's value minus the certified lower bound (at least 0)."""
        return max(0.0, self.value - self.lower_bound)

    def summary(self) -> str:
        """One line: ``proven optimal: VALUE`` or the certified gap."""
        if self.integral and self.proven:
            return f"proven optimal: {self.value:.12g}"
        pct = 100 * self.gap / max(abs(self.value), 1e-12)
        if self.proven:
            return f"proven optimal: {self.value:.10g} (certified gap {self.gap:.3g}, {pct:.2g} %)"
        return (f"not optimal as certified: tour {self.value:.10g}, every tour costs more than "
                f"{float(self.cutoff):.10g} (gap {self.gap:.6g}, {pct:.4g} %)")


def _field(cert: dict[str, Any], key: str, kind: type | tuple[type, ...]) -> Any:
    value = cert.get(key)
    if not isinstance(value, kind) or value is True or value is False:
        raise InputError(f"certificate field {key!r} is missing or malformed")
    return value


class ProofChecker:
    """The steps of a check that a tree walk takes: each proof's reduced costs (a few kept in a
    cache: a parent's proof often closes its children), closing a node, applying a fixing.

    Parameters
    ----------
    space
        The model's columns and costs.
    cuts
        The certificate's cuts, parsed (:func:`~gtsp_bench.proof.families.parse_cut`).
    proofs
        The proofs in version 1's layout.
    bits
        The dual scale: every dual is an integer over ``2**bits``.
    cutoff
        Every tour must be shown to cost more than this.
    uses
        When given, each proof's uses are recorded in it: ``uses[k]`` lists ``("close", domain)``
        for a domain the proof must bound above the cutoff and ``("rule", domain, ys, xs)`` for a
        reduced-cost fixing (the domain before it, the columns it fixed).

    A proof (version 1's layout) may carry its own scale as ``"bits"``, else ``bits`` applies.
    """

    def __init__(self, space: Space, cuts: list[Cut], proofs: list[Any], bits: int,
                 cutoff: Fraction, uses: dict[int, list[tuple[Any, ...]]] | None = None) -> None:
        self.space, self.cuts, self.proofs, self.bits, self.cutoff = space, cuts, proofs, bits, cutoff
        self.cache: OrderedDict[int, Priced] = OrderedDict()
        self.uses = uses

    def priced(self, k: Any, where: str) -> Priced:
        """The reduced costs of proof ``k`` (``where`` names the step for an error)."""
        if not is_int(k) or not 0 <= k < len(self.proofs):
            raise ProofError(f"{where}: proof {k!r} does not exist")
        if k in self.cache:
            self.cache.move_to_end(k)
            return self.cache[k]
        proof = self.proofs[k]
        bits = proof.get("bits", self.bits) if isinstance(proof, dict) else self.bits
        if not is_int(bits) or not 0 <= bits <= 60:
            raise ProofError(f"{where}: proof {k}: its scale 'bits' must be an integer in [0, 60]")
        try:
            p = price_duals(self.space, self.cuts, proof, bits)
        except ValueError as e:
            raise ProofError(f"{where}: proof {k}: {e}") from None
        self.cache[k] = p
        if len(self.cache) > _CACHE:
            self.cache.popitem(last=False)
        return p

    def closes(self, k: Any, domain: Domain, where: str) -> None:
        """Check that proof ``k`` bounds ``domain`` above the cutoff (or shows it empty)."""
        p = self.priced(k, where)
        if self.uses is not None:
            self.uses.setdefault(k, []).append(("close", domain.copy()))
        b = p.bound(domain)
        if p.farkas and b <= 0:
            raise ProofError(f"{where}: Farkas proof {k} has value {float(b):.6g}, not above 0 "
                             "(it does not show the node empty)")
        if not p.farkas and b <= self.cutoff:
            raise ProofError(f"{where}: proof {k} bounds it at {float(b):.10g}, not above the "
                             f"cutoff {float(self.cutoff):.10g}")

    def var(self, v: Any, where: str) -> tuple[int, int]:
        """``(i, j)`` of a variable of the certificate (:func:`~gtsp_bench.proof.format.parse_var`)."""
        try:
            return parse_var(v, self.space.n_nodes, self.space.cluster_of)
        except ValueError as e:
            raise ProofError(f"{where}: {e}") from None

    def fix(self, fixing: Any, domain: Domain, where: str) -> bool:
        """Apply one ``fix`` entry to ``domain`` after checking its proof; whether it leaves no
        tour below the cutoff in the node (it fixes a variable the other way than an earlier
        fixing did)."""
        if not isinstance(fixing, dict):
            raise ProofError(f"{where}: a fixing must be an object")
        k = fixing.get("proof")
        if fixing.get("rule") == "reduced_cost":
            p = self.priced(k, where)
            if p.farkas:
                raise ProofError(f"{where}: reduced-cost fixing needs a dual proof, not Farkas")
            room = self.cutoff - p.bound(domain)
            ys, (xi, xj) = p.fixable(domain, room)
            if self.uses is not None:
                self.uses.setdefault(k, []).append(("rule", domain.copy(), ys, (xi, xj)))
            domain.y[ys] = 0
            domain.x[xi, xj] = 0
            return False
        entries = fixing.get("vars")
        if not isinstance(entries, list) or not entries:
            raise ProofError(f"{where}: a fixing needs 'rule': 'reduced_cost' or a list 'vars'")
        for e in entries:
            if not isinstance(e, list) or len(e) != 2 or e[1] not in (0, 1):
                raise ProofError(f"{where}: fixing {e!r} is not [variable, 0 or 1]")
            i, j = self.var(e[0], where)
            if domain.get(i, j) == e[1]:
                continue
            if domain.get(i, j) != -1:  # fixed the other way: no tour below the cutoff is here
                return True
            other = domain.copy()
            other.set(i, j, 1 - e[1])
            self.closes(k, other, f"{where}, fixing {var_name(i, j)} = {e[1]}")
            domain.set(i, j, e[1])
        return False


def _tree(nodes: Any) -> dict[int, list[int]]:
    """Children of each node, each node's parent checked to come before it."""
    if not isinstance(nodes, list) or not nodes:
        raise InputError("certificate field 'nodes' is missing or empty")
    children: dict[int, list[int]] = {k: [] for k in range(len(nodes))}
    for k, node in enumerate(nodes):
        if not isinstance(node, dict):
            raise ProofError(f"node {k}: not an object")
        parent = node.get("parent")
        if k == 0:
            if parent is not None or "branch" in node:
                raise ProofError("node 0 (the root) has a parent or a branching")
            continue
        if not is_int(parent) or not 0 <= parent < k:
            raise ProofError(f"node {k}: its parent must be an earlier node")
        children[parent].append(k)
    return children


def check_certificate(instance: Instance, cert: dict[str, Any],
                      uses: dict[int, list[tuple[Any, ...]]] | None = None,
                      on_node: Callable[[int, int], None] | None = None) -> CheckResult:
    """Check a certificate against an instance.

    Parameters
    ----------
    instance
        The instance (its file as read by :func:`gtsp_bench.data.io.read_instance`).
    cert
        The certificate (:func:`gtsp_bench.proof.format.read_certificate`).
    uses
        When given, what each proof is used for is recorded in it (see :class:`ProofChecker`).
    on_node
        When given, called after each node of the tree with the nodes walked and the nodes in
        all (a progress bar's feed).

    Returns
    -------
    CheckResult
        What it proves.

    Raises
    ------
    InputError
        A certificate for another instance or with malformed top-level fields.
    ProofError
        The first step that fails.
    """
    head = _field(cert, "instance", dict)
    problem = price(instance, head.get("omega"))
    if (head.get("nodes") != problem.n_nodes or head.get("clusters") != problem.n_clusters
            or head.get("costs_sha256") != fingerprint(problem)):
        raise InputError(f"the certificate is for instance {head.get('name')!r}, whose costs differ "
                         f"from {instance.name!r}'s")
    if problem.n_clusters < 3:
        raise ProofError("the cut families need at least 3 clusters")
    space = Space.of(problem)
    tour = _field(cert, "tour", list)
    try:
        order, heads = problem.to_solution(tour)
    except (InfeasibleSolutionError, TypeError, ValueError) as e:
        raise ProofError(f"tour: not a tour ({e})") from None
    value = evaluate(instance, problem.omega, order, heads).objective
    claimed = float(_field(cert, "value", (int, float)))
    if abs(value - claimed) > 1e-9 * max(1.0, abs(value)):
        raise ProofError(f"tour: the certificate prices it at {claimed:.10g}, the evaluator at "
                         f"{value:.10g}")
    cutoff = Fraction(_field(cert, "cutoff", (int, float)))
    bits = _field(cert, "dual_bits", int)
    if not 0 <= bits <= 60:
        raise InputError("certificate field 'dual_bits' must be in [0, 60]")
    version = cert.get("version", 1)
    if version not in READABLE:
        raise InputError(f"certificate version {version!r}; this checker reads versions "
                         f"{', '.join(map(str, READABLE))}")
    cuts = []
    for k, c in enumerate(_field(cert, "cuts", list)):
        try:
            cuts.append(parse_cut(decode_cut(c) if version == 2 else c, space.cluster_of))
        except ValueError as e:
            raise ProofError(f"cut {k}: {e}") from None
    proofs = _field(cert, "proofs", list)
    if version == 2:
        try:
            proofs = decode_proofs(proofs, problem.n_clusters, problem.n_nodes, bits)
        except ValueError as e:
            raise ProofError(str(e)) from None
    nodes = cert.get("nodes")
    children = _tree(nodes)
    checker = ProofChecker(space, cuts, proofs, bits, cutoff, uses)
    stack: list[tuple[int, Domain | None]] = [(0, Domain.free(space))]
    seen = leaves = 0
    while stack:
        k, domain = stack.pop()
        seen += 1
        if on_node is not None:
            on_node(seen, len(nodes))
        kids = children[k]
        if domain is None:  # below a node holding no tour under the cutoff: nothing to check
            stack.extend((c, None) for c in kids)
            continue
        node, where = nodes[k], f"node {k}"
        fixes = node.get("fix", [])
        if any(checker.fix(f, domain, where) for f in (fixes if isinstance(fixes, list) else [None])):
            stack.extend((c, None) for c in kids)
            continue
        if "proof" in node:
            if kids:
                raise ProofError(f"{where}: a leaf with children")
            checker.closes(node["proof"], domain, f"{where} (leaf)")
            leaves += 1
            continue
        if not kids:
            raise ProofError(f"{where}: neither a leaf proof nor children (the tree does not cover it)")
        branches = []
        for c in kids:
            b = nodes[c].get("branch")
            if not isinstance(b, list) or len(b) != 2 or b[1] not in (0, 1):
                raise ProofError(f"node {c}: its branching is not [variable, 0 or 1]")
            branches.append((checker.var(b[0], f"node {c}"), b[1], c))
        var = branches[0][0]
        name = var_name(*var)
        if any(b[0] != var for b in branches) or len(branches) > 2:
            raise ProofError(f"{where}: its children do not branch on one variable")
        values = {b[1] for b in branches}
        for v in (0, 1):
            if v not in values:
                raise ProofError(f"{where}: branch on {name} lacks its child {name} = {v} "
                                 "(the leaves do not cover the space)")
        state = domain.get(*var)  # fixed by a fixing: the other child holds no tour below the cutoff
        for b in branches:
            if state not in (-1, b[1]):
                stack.append((b[2], None))
                continue
            child = domain.copy()
            child.set(*var, b[1])
            stack.append((b[2], child))
    if seen != len(nodes):
        raise ProofError(f"{len(nodes) - seen} nodes are not reached from the root")
    if space.integral:
        proven = math.floor(cutoff) + 1 >= value
    else:
        proven = value - float(cutoff) <= FLOAT_GAP * max(1.0, abs(value))
    return CheckResult(value, cutoff, space.integral, proven, len(nodes), leaves)
