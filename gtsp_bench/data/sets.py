"""Instance sets beyond the paper's experiments, and the reference values they carry.

A *set* is a folder of instance files (``.json``, ``.gtsp``, either gzip-compressed). A committed
set is a folder under ``instances/`` named by its folder (``uav-K50-N20-s1``); ``gtsplib`` names
the bundled GTSPLIB (:mod:`gtsp_bench.data.gtsplib`); any other folder, or a single instance file, is a
set too (:func:`resolve_set`).

A set's reference values live in ``reference.csv`` beside its files, one row per instance and
omega::

    instance,omega,value,lower_bound,status,source,date
    my-set-000,0.5,48123.25,47990.5,best_known,lns 30s seed 0,2026-11-23

``instance`` is the file's stem (its name without ``.json`` / ``.gtsp`` / ``.gz``); ``omega`` is
empty for a distance-only (GTSPLIB) instance; ``value`` is the objective and ``lower_bound``
(may be empty) a proven bound; ``status`` is ``optimal`` (a proven optimum) or ``best_known``
(the best tour known, not proven); ``source`` says where the value comes from (``milp 60s``,
``GLKH``, ...) and ``date`` when (ISO ``yyyy-mm-dd``). :func:`parse_reference` reads the text
strictly (one-line errors naming the line), :func:`read_reference` and :func:`write_reference`
do the file I/O, the latter atomically.

GTSPLIB keeps one source of truth: its set's references are read from the library's own
``best_known.csv`` (GLKH's tour lengths, or a shorter tour's kept since, with the same
``optimal`` / ``best_known`` status, source and date), which also names a tour file per value; no
``reference.csv`` is written for it (``--update-reference`` keeps a GTSPLIB tour there:
:mod:`gtsp_bench.bench.best_known`).
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from gtsp_bench.bench.tasks import fingerprint
from gtsp_bench.checks import strictly_better
from gtsp_bench.data.io import INSTANCE_SUFFIXES, atomic_write_text, format_suffix, instance_stem, read_text
from gtsp_bench.data.parse import parse_instance_text
from gtsp_bench.errors import InputError

if TYPE_CHECKING:
    from gtsp_bench.data.gtsplib import Reference

#: File name of a set's reference values.
REFERENCE_FILE = "reference.csv"
#: Its columns, in order (the header must be exactly this).
REFERENCE_COLUMNS = ("instance", "omega", "value", "lower_bound", "status", "source", "date")
#: Values of :attr:`ReferenceRow.status`.
STATUSES = ("optimal", "best_known")
#: The name of the bundled GTSPLIB set.
GTSPLIB = "gtsplib"
#: The committed UAV set of K clusters of 20 nodes (K = 4..10, 20, 50, 100, 200).
UAV_SET = "uav-K{k}-N20-s1"
_DATE = re.compile(r"\d{4}-\d{2}-\d{2}")


# ---------------------------------------------------------------------- reference.csv
@dataclass(frozen=True)
class ReferenceRow:
    """One reference value: the objective of ``instance`` at ``omega`` (``None``: distance-only)."""

    instance: str
    omega: float | None
    value: float
    lower_bound: float | None
    status: str
    source: str
    date: str

    @property
    def key(self) -> tuple[str, float | None]:
        """``(instance, omega)``: what a row is looked up by."""
        return self.instance, self.omega

    @property
    def label(self) -> str:
        """How a gap against it reads: ``to optimum`` or ``to best known``."""
        return "to optimum" if self.status == "optimal" else "to best known"


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{what} {text!r} is not a number") from None
    if not math.isfinite(value):
        raise InputError(f"{what} {text!r} is not finite")
    return value


def _row(fields: Sequence[str]) -> ReferenceRow:
    instance, omega_t, value_t, lb_t, status, source, date = (f.strip() for f in fields)
    if not instance:
        raise InputError("empty instance name")
    omega = None
    if omega_t:
        omega = _number(omega_t, "omega")
        if not 0.0 <= omega <= 1.0:
            raise InputError(f"omega {omega_t!r} is not in [0, 1]")
    value = _number(value_t, "value")
    lower = _number(lb_t, "lower_bound") if lb_t else None
    if lower is not None and strictly_better(value, lower):
        raise InputError(f"lower_bound {lb_t} is above the value {value_t}")
    if status not in STATUSES:
        raise InputError(f"status {status!r} is not one of {', '.join(STATUSES)}")
    if not source:
        raise InputError("empty source")
    try:
        if not _DATE.fullmatch(date):
            raise ValueError
        dt.date.fromisoformat(date)
    except ValueError:
        raise InputError(f"date {date!r} is not an ISO date yyyy-mm-dd") from None
    return ReferenceRow(instance, omega, value, lower, status, source, date)


def parse_reference(text: str) -> dict[tuple[str, float | None], ReferenceRow]:
    """The rows of a ``reference.csv`` text by ``(instance, omega)``, in file order.

    Raises
    ------
    InputError
        ``"line N: problem"`` for a header other than :data:`REFERENCE_COLUMNS`, a row with the
        wrong number of fields, a bad number, omega, status or date, an empty instance or source,
        a lower bound above the value, or an ``(instance, omega)`` listed twice.
    """
    rows = list(csv.reader(io.StringIO(text)))
    if not rows or [c.strip() for c in rows[0]] != list(REFERENCE_COLUMNS):
        got = ",".join(rows[0]) if rows else "nothing"
        raise InputError(f"line 1: header must be {','.join(REFERENCE_COLUMNS)}, got {got!r}")
    out: dict[tuple[str, float | None], ReferenceRow] = {}
    for line, fields in enumerate(rows[1:], start=2):
        if not fields or not "".join(fields).strip():
            continue
        if len(fields) != len(REFERENCE_COLUMNS):
            raise InputError(f"line {line}: {len(fields)} fields, expected {len(REFERENCE_COLUMNS)}")
        try:
            ref = _row(fields)
        except InputError as e:
            raise InputError(f"line {line}: {e}") from None
        if ref.key in out:
            w = "" if ref.omega is None else f" at omega {ref.omega:g}"
            raise InputError(f"line {line}: {ref.instance}{w} is listed twice")
        out[ref.key] = ref
    return out


def _format_number(value: float | None, integral: bool) -> str:
    if value is None:
        return ""
    if integral and float(value).is_integer():
        return str(int(value))
    return repr(float(value))


def format_reference(rows: Iterable[ReferenceRow]) -> str:
    """The ``reference.csv`` text of ``rows`` (values as ``repr`` floats; whole numbers of
    distance-only rows as integers); :func:`parse_reference` reads it back unchanged."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(REFERENCE_COLUMNS)
    for r in rows:
        integral = r.omega is None
        w.writerow([r.instance, "" if r.omega is None else repr(float(r.omega)),
                    _format_number(r.value, integral), _format_number(r.lower_bound, integral),
                    r.status, r.source, r.date])
    return buf.getvalue()


def read_reference(path: str | os.PathLike[str]) -> dict[tuple[str, float | None], ReferenceRow]:
    """The reference rows of a file; none when it does not exist.

    Raises
    ------
    InputError
        ``"<path>: line N: problem"`` for a malformed file (see :func:`parse_reference`).
    """
    p = Path(path)
    if not p.exists():
        return {}
    try:
        return parse_reference(read_text(p))
    except InputError as e:
        text = str(e)
        raise InputError(text if text.startswith(f"{p}:") else f"{p}: {text}") from None


def write_reference(path: str | os.PathLike[str], rows: Iterable[ReferenceRow]) -> None:
    """Write ``rows`` as a ``reference.csv``, atomically."""
    atomic_write_text(path, format_reference(rows))


# ---------------------------------------------------------------------- sets
@dataclass(frozen=True)
class SetFile:
    """One instance file of a set, before it is read; ``clusters`` and ``nodes`` when known
    without reading it (GTSPLIB's table)."""

    path: Path
    stem: str
    clusters: int | None = None
    nodes: int | None = None


@dataclass(frozen=True)
class InstanceSet:
    """A resolved ``--set``: its label, folder, files (in order) and reference values.

    ``reference_path`` is the file improvements are written to (``None`` for GTSPLIB, whose
    values are GLKH's tours in ``best_known.csv``).
    """

    name: str
    folder: Path
    files: tuple[SetFile, ...]
    references: Mapping[tuple[str, float | None], ReferenceRow]
    reference_path: Path | None


def _is_instance_file(p: Path) -> bool:
    return p.is_file() and not p.name.startswith(".") and format_suffix(p) in INSTANCE_SUFFIXES


def committed_sets(instance_dir: Path) -> list[str]:
    """The committed sets: folders of ``instance_dir`` holding instance files, and ``gtsplib``."""
    names = {GTSPLIB}
    if instance_dir.is_dir():
        names |= {d.name for d in instance_dir.iterdir()
                  if d.is_dir() and any(_is_instance_file(f) for f in d.iterdir())}
    return sorted(names)


def gtsplib_reference_row(r: Reference) -> ReferenceRow:
    """A GTSPLIB file's ``best_known.csv`` row as the reference a solve of it is measured
    against (distance-only: omega ``None``)."""
    return ReferenceRow(r.name, None, r.value, None, r.status, r.reference_source, r.date)


def _gtsplib_set(where: Path | None, name: str) -> InstanceSet:
    from gtsp_bench.data import gtsplib

    if where is None:
        where = gtsplib.folder()
        table = gtsplib.best_known()
    else:
        try:
            table = gtsplib.parse_best_known((where / "best_known.csv").read_text(encoding="utf-8"))
        except InputError as e:
            raise InputError(f"{where / 'best_known.csv'}: {e}") from None
    files, refs = [], {}
    for r in table.values():  # AGTSP files too: symmetric-only solvers refuse them
        files.append(SetFile(where / f"{r.name}.gtsp.gz", r.name, r.clusters, r.nodes))
        refs[(r.name, None)] = gtsplib_reference_row(r)
    return InstanceSet(name, where, tuple(files), refs, None)


def resolve_set(arg: str, instance_dir: str | os.PathLike[str] = "instances") -> InstanceSet:
    """The set a ``--set`` argument names.

    ``gtsplib`` is the bundled GTSPLIB (all 143 instances, asymmetric ones included, smallest
    first); a name of a
    folder under ``instance_dir`` a committed set; otherwise a folder path (its instance files in
    name order; a folder with GTSPLIB's ``best_known.csv`` and no ``reference.csv`` is read as
    GTSPLIB) or a single instance file (its folder's ``reference.csv`` applies).

    Raises
    ------
    InputError
        When nothing of that name exists (listing the committed sets), the folder holds no
        instance file, or its ``reference.csv`` is malformed.
    """
    base = Path(instance_dir)
    text = str(arg).strip()
    if not text:
        raise InputError("--set: empty set name")
    if text == GTSPLIB and not Path(text).exists():
        return _gtsplib_set(None, GTSPLIB)
    path = base / text if (base / text).is_dir() and os.sep not in text else Path(text)
    if path.is_file():
        if not _is_instance_file(path):
            raise InputError(f"{path}: not an instance file (.json or .gtsp, optionally .gz)")
        ref_path = path.parent / REFERENCE_FILE
        return InstanceSet(instance_stem(path), path.parent, (SetFile(path, instance_stem(path)),),
                           read_reference(ref_path), ref_path)
    if not path.is_dir():
        raise InputError(f"unknown set {text!r}: no such folder or file (committed sets: "
                         f"{', '.join(committed_sets(base))}; or a folder of .json / .gtsp(.gz) files)")
    ref_path = path / REFERENCE_FILE
    if (path / "best_known.csv").is_file() and not ref_path.exists():
        return _gtsplib_set(path, path.name)
    files = tuple(SetFile(f, instance_stem(f)) for f in sorted(path.iterdir()) if _is_instance_file(f))
    if not files:
        raise InputError(f"{path}: no instance files (.json or .gtsp, optionally .gz) in this folder")
    seen: dict[str, Path] = {}
    for f in files:
        if f.stem in seen:
            raise InputError(f"{f.path}: same instance name as {seen[f.stem].name}")
        seen[f.stem] = f.path
    return InstanceSet(path.name, path, files, read_reference(ref_path), ref_path)


def uav_set(k: int, instance_dir: str | os.PathLike[str] = "instances") -> InstanceSet:
    """The committed UAV set of K clusters (:data:`UAV_SET`).

    Raises
    ------
    InputError
        When there is none for this K (the message lists the committed sets).
    """
    return resolve_set(UAV_SET.format(k=k), instance_dir)


def read_set_file(f: SetFile) -> tuple[object, str, str]:
    """``(instance, text, fingerprint)`` of a set's file: the parsed instance, its (gunzipped)
    text and the first 16 hex digits of its SHA-256, as the paper's runner fingerprints."""
    text = read_text(f.path)
    try:
        inst = parse_instance_text(text, default_name=f.stem)
    except InputError as e:
        raise InputError(f"{f.path}: {e}") from None
    return inst, text, fingerprint(text)


# ---------------------------------------------------------------------- improvements
@dataclass(frozen=True)
class Improvement:
    """A tour better than a set's reference: ``objective`` by ``solver`` (seed, time limit)."""

    set_name: str
    instance: str
    omega: float | None
    objective: float
    solver: str
    seed: int
    time_limit: float


def apply_improvements(rows: Mapping[tuple[str, float | None], ReferenceRow],
                       found: Iterable[Improvement], today: str) -> tuple[list[ReferenceRow], list[str]]:
    """The rows with each strictly better ``best_known`` value replaced; and what changed.

    The best improvement per ``(instance, omega)`` wins. A row whose status is ``optimal`` is
    never changed; a value below it raises.

    Raises
    ------
    InputError
        A tour below a proven optimum (the reference or the solver is wrong).
    """
    best: dict[tuple[str, float | None], Improvement] = {}
    for imp in found:
        key = (imp.instance, imp.omega)
        if key not in best or imp.objective < best[key].objective:
            best[key] = imp
    out, changes = [], []
    for key, row in rows.items():
        imp = best.get(key)
        if imp is None or not strictly_better(imp.objective, row.value):
            out.append(row)
            continue
        if row.status == "optimal":
            raise InputError(f"{imp.instance}: {imp.solver} found {imp.objective!r}, below the proven "
                             f"optimum {row.value!r}; the reference or the solver is wrong")
        source = f"{imp.solver} {imp.time_limit:g}s seed {imp.seed}"
        lower = row.lower_bound
        out.append(ReferenceRow(row.instance, row.omega, imp.objective, lower, "best_known", source, today))
        changes.append(f"{row.instance}{'' if row.omega is None else f' omega {row.omega:g}'}: "
                       f"{row.value!r} -> {imp.objective!r} ({source})")
    return out, changes


def update_reference(path: Path, found: Sequence[Improvement], today: str | None = None) -> list[str]:
    """Write the improvements in ``found`` into the ``reference.csv`` at ``path`` (re-read just
    before writing), atomically; returns one line per changed row (none: the file is untouched)."""
    today = today or dt.datetime.now(dt.UTC).date().isoformat()
    rows = read_reference(path)
    try:
        new, changes = apply_improvements(rows, found, today)
    except InputError as e:
        raise InputError(f"{path}: {e}") from None
    if changes:
        write_reference(path, new)
    return changes
