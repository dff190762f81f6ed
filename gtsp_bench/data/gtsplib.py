"""The GTSPLIB benchmark library by name: instances, the best-known tours and reference values.

The library (143 instances, see ``instances/gtsplib/README.md``) is a folder of the source
repository, ``instances/gtsplib/``, not package data: an installed wheel does not hold it. The
folder is found beside this package in a source checkout (an editable install included), or where
the environment variable ``GTSP_BENCH_GTSPLIB`` points; otherwise every function here raises an
:class:`~gtsp_bench.errors.InputError` that says so.

>>> from gtsp_bench import gtsplib
>>> inst = gtsplib.read("11berlin52")
>>> gtsplib.best_known()["11berlin52"].value
4040.0
"""

from __future__ import annotations

import csv
import difflib
import io
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

from gtsp_bench.checks import strictly_better
from gtsp_bench.data.io import atomic_write_text, read_instance, read_tour, write_tour
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance

#: Environment variable naming the GTSPLIB folder (default: the repository's instances/gtsplib/).
ENV_VAR = "GTSP_BENCH_GTSPLIB"
#: The five instances the project's tests and benchmarks have always used (four proven optima
#: and one best known).
SAMPLES = ("11berlin52", "20kroA100", "40d198", "64lin318", "107att532")
#: The largest symmetric GTSPLIB files proven optimal in the literature have this many nodes
#: (Fischetti, Salazar-Gonzalez and Toth 1997); optima of larger ones are this package's proofs.
PUBLISHED_FRONTIER = 442
#: Values of :attr:`Reference.status`.
STATUSES = ("optimal", "best_known")

_REPO_FOLDER = Path(__file__).resolve().parents[2] / "instances" / "gtsplib"
_COLUMNS = ("name", "clusters", "nodes", "best_known", "status", "type", "edge_weight_type",
            "edge_weight_format", "tour")
#: Columns a table may leave out (older copies of the library): empty when absent.
_OPTIONAL = ("source", "date", "certificate", "published")


@dataclass(frozen=True)
class Reference:
    """One row of ``best_known.csv``.

    Attributes
    ----------
    name
        Instance name (``11berlin52``).
    clusters, nodes
        Its size.
    value
        The best-known objective: the length of :attr:`tour` (GLKH's best, or a shorter one
        kept since by :func:`keep_tour`).
    status
        ``"optimal"`` (a proven optimum: the symmetric instances up to 442 nodes, Fischetti et al.
        1997, and larger ones with a shipped :attr:`certificate`) or ``"best_known"`` (the best
        tour found, not proven optimal).
    type
        ``GTSP``, ``AGTSP`` (asymmetric costs) or ``TSP`` as the file says.
    edge_weight_type, edge_weight_format
        As the file says (the format is empty for coordinate types).
    tour
        The best tour's file, relative to the library folder.
    source
        Who found :attr:`tour` (``GLKH`` for the distributed tours, else the solver and options
        that found a better one, e.g. ``gtsp-bench lns seed 3``).
    date
        When :attr:`source` found it (ISO date; empty for the distributed tours).
    certificate
        A proof certificate of optimality (``gtsp-bench check-proof`` checks it), relative to the
        library folder; empty where none is shipped.
    published
        The value the library was distributed with (GLKH's tour length, the value GLNS and GLKH's
        papers compare against); :attr:`value` is lower where a shorter tour was kept since, and
        the tour of the published value stays as ``tours/NAME.PUBLISHED.tour.gz``. ``None`` in
        an older copy of the table without the column.
    """

    name: str
    clusters: int
    nodes: int
    value: float
    status: str
    type: str
    edge_weight_type: str
    edge_weight_format: str
    tour: str
    source: str = ""
    date: str = ""
    certificate: str = ""
    published: float | None = None

    @property
    def proven(self) -> bool:
        """Whether :attr:`value` is a proven optimum."""
        return self.status == "optimal"

    @property
    def reference_source(self) -> str:
        """Who proved :attr:`value` and whose tour it is, as a benchmark's rows name their
        reference: the literature's proof up to :data:`PUBLISHED_FRONTIER` nodes, beyond it the
        shipped certificate; a best known names its tour's source."""
        tour = self.source or "GLKH"
        if not self.proven:
            return tour
        if self.nodes > PUBLISHED_FRONTIER and self.certificate:
            return f"milp, certificate {self.certificate}; {tour} tour"
        return f"Fischetti et al. 1997; {tour} tour"

    @property
    def symmetric(self) -> bool:
        """Whether the instance's costs are symmetric (AGTSP files are not: only the solvers that
        handle asymmetric costs take them, see :func:`gtsp_bench.solver.handles_asymmetric`)."""
        return self.type != "AGTSP"


def parse_best_known(text: str) -> dict[str, Reference]:
    """The rows of a ``best_known.csv`` text by instance name, in file order.

    Raises
    ------
    InputError
        For a missing column, a bad number or status, or a name listed twice.
    """
    reader = csv.DictReader(io.StringIO(text))
    missing = [c for c in _COLUMNS if c not in (reader.fieldnames or [])]
    if missing:
        raise InputError(f"missing column {missing[0]!r}")
    out: dict[str, Reference] = {}
    for line, row in enumerate(reader, start=2):
        try:
            published = row.get("published") or None
            ref = Reference(row["name"], int(row["clusters"]), int(row["nodes"]),
                            float(row["best_known"]), row["status"], row["type"],
                            row["edge_weight_type"], row["edge_weight_format"], row["tour"],
                            *((row.get(c) or "") for c in _OPTIONAL[:-1]),
                            None if published is None else float(published))
        except (TypeError, ValueError):
            raise InputError(f"line {line}: bad row {row!r}") from None
        if ref.published is not None and not ref.value <= ref.published:
            raise InputError(f"line {line}: {ref.name}'s best_known {row['best_known']} is above its "
                             f"published value {row['published']}")
        if ref.status not in STATUSES:
            raise InputError(f"line {line}: status {ref.status!r} is not one of {', '.join(STATUSES)}")
        if ref.name in out:
            raise InputError(f"line {line}: {ref.name} is listed twice")
        out[ref.name] = ref
    return out


def format_best_known(references: Iterable[Reference]) -> str:
    """The text of a ``best_known.csv`` holding ``references`` in the given order (the inverse of
    :func:`parse_best_known`; integral values are written without a decimal point)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow((*_COLUMNS, *_OPTIONAL))
    for r in references:
        writer.writerow((r.name, r.clusters, r.nodes, _number(r.value), r.status, r.type,
                         r.edge_weight_type, r.edge_weight_format, r.tour, r.source, r.date,
                         r.certificate, "" if r.published is None else _number(r.published)))
    return out.getvalue()


def _number(value: float) -> float | int:
    """``value`` as written in the table: integral values without a decimal point."""
    return int(value) if float(value).is_integer() else value


def folder() -> Path:
    """The GTSPLIB folder (``$GTSP_BENCH_GTSPLIB``, else the repository's ``instances/gtsplib``).

    Raises
    ------
    InputError
        If it has no ``best_known.csv``: the library ships with the source repository, not the wheel.
    """
    env = os.environ.get(ENV_VAR)
    where = Path(env) if env else _REPO_FOLDER
    if not (where / "best_known.csv").is_file():
        how = f"${ENV_VAR} points to {where}" if env else f"looked in {where}"
        raise InputError(
            f"GTSPLIB not found ({how}, no best_known.csv there): the library is the folder "
            f"instances/gtsplib/ of the gtsp-bench source repository, not part of the installed "
            f"package; set {ENV_VAR} to a copy of it"
        )
    return where


def read_best_known(where: Path) -> dict[str, Reference]:
    """The table ``where/best_known.csv`` (read now, not cached).

    Raises
    ------
    InputError
        ``FILE: problem``: the table is unreadable or malformed.
    """
    table = where / "best_known.csv"
    try:
        return parse_best_known(table.read_text(encoding="utf-8"))
    except InputError as e:
        raise InputError(f"{table}: {e}") from None
    except OSError as e:
        raise InputError(f"{table}: cannot read it ({e.strerror or e})") from None


@lru_cache(maxsize=4)
def _best_known(where: Path) -> dict[str, Reference]:
    return read_best_known(where)


def best_known() -> dict[str, Reference]:
    """Every instance's reference value by name (a fresh dict; the rows are frozen)."""
    return dict(_best_known(folder()))


def names() -> list[str]:
    """All instance names, smallest first (the order of ``best_known.csv``)."""
    return list(_best_known(folder()))


def _reference(name: str) -> Reference:
    table = _best_known(folder())
    if name not in table:
        close = difflib.get_close_matches(name, table, n=3)
        hint = f"did you mean {', '.join(close)}? " if close else ""
        raise InputError(f"unknown GTSPLIB instance {name!r} ({hint}{len(table)} instances: "
                         "see gtsp_bench.data.gtsplib.names())")
    return table[name]


def path(name: str) -> Path:
    """The instance file of ``name`` (``<folder>/<name>.gtsp.gz``)."""
    _reference(name)
    return folder() / f"{name}.gtsp.gz"


def tour_path(name: str) -> Path:
    """The best-known tour file of ``name`` (:attr:`Reference.tour`)."""
    return folder() / _reference(name).tour


def read(name: str) -> Instance:
    """Read the instance ``name``."""
    return read_instance(path(name))


def best_tour(name: str, instance: Instance | None = None) -> tuple[list[int], list[int]]:
    """The best-known tour of ``name`` (GLKH's, or a better one kept since, :func:`keep_tour`) as
    ``(order, heads)`` of ``instance`` (default: read it)."""
    return read_tour(tour_path(name), read(name) if instance is None else instance)


def keep_tour(where: Path, name: str, order: Sequence[int], heads: Sequence[int], source: str,
              date: str) -> Reference | None:
    """Keep a tour of ``name`` that is shorter than its ``best_known`` value: write it to
    ``where/tours/NAME.LENGTH.tour.gz`` and point its row of ``where/best_known.csv`` at it (the
    value, tour, ``source`` and ``date``; the status, certificate and published value unchanged,
    the latter filled with the old value where the table had none), both atomically.

    The tour is priced here by the evaluator on the library's file, whatever its finder claimed.
    The earlier tour file stays (``published`` names GLKH's; git keeps who found what). Returns
    the new row, or ``None`` when the tour is not shorter.

    Raises
    ------
    InputError
        ``FILE: problem``: an unreadable table, an unknown name, an infeasible tour, or one
        shorter than a proven optimum (the solver or the table is wrong).
    """
    table_path = where / "best_known.csv"
    table = read_best_known(where)
    if name not in table:
        raise InputError(f"{table_path}: no instance {name!r}")
    ref = table[name]
    file = where / f"{name}.gtsp.gz"
    inst = read_instance(file)
    try:
        length = evaluate(inst, None, order, heads).objective
    except InputError as e:
        raise InputError(f"{file}: the tour to keep is not one: {e}") from None
    if not strictly_better(length, ref.value):
        return None
    if ref.proven:
        raise InputError(f"{table_path}: {name}: a tour of length {length!r} lies below the proven "
                         f"optimum {ref.value!r}; the solver or the table is wrong")
    value = _number(length)
    tour = f"tours/{name}.{value}.tour.gz"
    write_tour(inst, where / tour, order, heads, [f"Length = {value}", f"Found by {source} {date}"])
    published = ref.value if ref.published is None else ref.published
    table[name] = replace(ref, value=float(length), tour=tour, source=source, date=date,
                          published=published)
    try:
        atomic_write_text(table_path, format_best_known(table.values()))
    except OSError as e:
        raise InputError(f"{table_path}: cannot write it ({e.strerror or e})") from None
    _best_known.cache_clear()
    return table[name]
