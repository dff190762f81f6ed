"""The ``gtsp-bench check-proof`` command: check a proof certificate (:mod:`gtsp_bench.proof`).

It prints ``proven optimal: VALUE`` (or, for float costs, the certified gap) and exits 0, or
prints ``not proven: <the first step that fails>`` and exits 1; an unreadable certificate or one
for another instance is bad input (exit 2, one line on stderr, from :mod:`gtsp_bench.cli`).
"""

from __future__ import annotations

import argparse
import sys
from typing import TextIO

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
    return p


def run_check_proof(args: argparse.Namespace, out: TextIO) -> int:
    """Check ``args.certificate`` against ``args.instance``, writing the answer line on ``out``;
    the exit code."""
    from gtsp_bench.data.io import read_instance
    from gtsp_bench.errors import InputError
    from gtsp_bench.proof import ProofError, check_certificate
    from gtsp_bench.proof.format import read_certificate

    instance = read_instance(args.instance)
    cert = read_certificate(args.certificate)
    try:
        result = check_certificate(instance, cert)
    except InputError as e:
        raise InputError(f"{args.certificate}: {e}") from None
    except ProofError as e:
        out.write(f"not proven: {e}\n")
        print(f"gtsp-bench: {args.certificate}: the certificate fails: {e}", file=sys.stderr)
        return 1
    out.write(result.summary() + "\n")
    return 0 if result.proven or not result.integral else 1
