"""The ``gtsp-bench check-proof`` command: check a proof certificate (:mod:`gtsp_bench.proof`).

It prints ``proven optimal: VALUE`` (or, for float costs, the certified gap) and exits 0, or
prints ``not proven: <the first step that fails>`` and exits 1; an unreadable certificate or one
for another instance is bad input (exit 2, one line on stderr, from :mod:`gtsp_bench.cli`). On a
terminal a bar on stderr counts the tree's nodes (``--no-progress``: none).
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any, TextIO

if TYPE_CHECKING:
    from gtsp_bench.instance import Instance
    from gtsp_bench.proof import CheckResult

DESCRIPTION = """\
Check a proof certificate written by 'gtsp-bench solve FILE --solver milp --certificate CERT':
every leaf bound is re-derived from its dual values in exact rational arithmetic (no LP solver),
every cut is checked by its family and sets, the leaves must cover the whole search space, and
the tour is re-priced by the shared evaluator. Exit 0 when the certificate proves its claim, 1
(naming the first step that fails) when not, 2 for an unreadable certificate or another instance.
"""


def add_check_proof_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``check-proof`` sub-command to the CLI's sub-parsers; its parser."""
    p = sub.add_parser("check-proof", help="check a proof certificate of optimality",
                       description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("instance", metavar="INSTANCE", help="the instance file the proof is about")
    p.add_argument("certificate", metavar="CERT", help="the certificate (.cert.json.gz)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar (by default one counts the tree's nodes on stderr when it "
                        "is a terminal; GTSPLIB's largest proofs take about a minute)")
    return p


def _check(instance: Instance, cert: dict[str, Any], progress: bool) -> CheckResult:
    """:func:`~gtsp_bench.proof.check_certificate` with a bar counting the tree's nodes on stderr
    (only where it is a terminal; closed before any message)."""
    from tqdm import tqdm

    from gtsp_bench.proof import check_certificate

    bar = None

    def on_node(seen: int, total: int) -> None:
        nonlocal bar
        if bar is None:
            bar = tqdm(total=total, unit="node", leave=False, dynamic_ncols=True,
                       disable=None if progress else True)  # None: on a terminal only
        bar.update(1)

    try:
        return check_certificate(instance, cert, on_node=on_node)
    finally:
        if bar is not None:
            bar.close()


def run_check_proof(args: argparse.Namespace, out: TextIO) -> int:
    """Check ``args.certificate`` against ``args.instance``, writing the answer line on ``out``;
    the exit code."""
    from gtsp_bench.data.io import read_instance
    from gtsp_bench.errors import InputError
    from gtsp_bench.proof import ProofError
    from gtsp_bench.proof.format import read_certificate

    instance = read_instance(args.instance)
    cert = read_certificate(args.certificate)
    try:
        result = _check(instance, cert, progress=not args.no_progress)
    except InputError as e:
        raise InputError(f"{args.certificate}: {e}") from None
    except ProofError as e:
        out.write(f"not proven: {e}\n")
        print(f"gtsp-bench: {args.certificate}: the certificate fails: {e}", file=sys.stderr)
        return 1
    out.write(result.summary() + "\n")
    return 0 if result.proven or not result.integral else 1
