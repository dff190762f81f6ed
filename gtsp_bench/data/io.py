"""Reading and writing files. Parsing lives in :mod:`gtsp_bench.data.parse`; this module opens files,
prefixes errors with the file name, and writes atomically (a temporary file, then a rename).

A file whose name ends in ``.gz`` (``11berlin52.gtsp.gz``) is gzip-compressed: it is read and
written transparently, its format named by the suffix before ``.gz``.
"""

from __future__ import annotations

import gzip
import json
import os
import secrets
import zlib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from gtsp_bench.data.parse import (
    format_gtsp,
    format_json_instance,
    format_tour,
    parse_gtsp,
    parse_json_instance,
    parse_solution,
    parse_tour,
    tour_to_solution,
)
from gtsp_bench.errors import InfeasibleSolutionError, InputError
from gtsp_bench.instance import Instance

#: Instance file suffixes this package reads and writes, each also gzip-compressed (``+ ".gz"``).
INSTANCE_SUFFIXES = (".json", ".gtsp")
#: Suffix of a gzip-compressed file.
GZIP_SUFFIX = ".gz"
#: Suffix of a TSPLIB tour file (GTSPLIB's best tours, and the tours ``solve --tour`` writes).
TOUR_SUFFIX = ".tour"


def format_suffix(path: str | os.PathLike[str]) -> str:
    """The suffix that names a file's format, lower case: ``.gtsp`` for ``x.gtsp`` and ``x.gtsp.gz``."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == GZIP_SUFFIX:
        suffix = Path(p.stem).suffix.lower()
    return suffix


def _instance_suffix(p: Path) -> str:
    suffix = format_suffix(p)
    if suffix not in INSTANCE_SUFFIXES:
        raise InputError(f"{p}: unknown instance format (expected {' or '.join(INSTANCE_SUFFIXES)}, "
                         f"optionally gzip-compressed as {INSTANCE_SUFFIXES[-1]}{GZIP_SUFFIX})")
    return suffix


def instance_stem(path: str | os.PathLike[str]) -> str:
    """A file's name without its format suffixes: ``11berlin52`` for ``11berlin52.gtsp.gz``."""
    name = Path(path).name
    if name.lower().endswith(GZIP_SUFFIX):
        name = name[: -len(GZIP_SUFFIX)]
    return Path(name).stem


def _read_text(path: Path) -> str:
    """The UTF-8 text of a file, gunzipped if its name ends in ``.gz``."""
    try:
        if path.suffix.lower() == GZIP_SUFFIX:
            return _gunzip(path, path.read_bytes()).decode("utf-8")
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, not a file") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e.strerror})") from None


def read_text(path: str | os.PathLike[str]) -> str:
    """The UTF-8 text of a file, gunzipped if its name ends in ``.gz``.

    Raises
    ------
    InputError
        ``"<path>: <problem>"`` for a missing, unreadable, non-UTF-8 or bad gzip file.
    """
    return _read_text(Path(path))


def _gunzip(path: Path, data: bytes) -> bytes:
    try:
        return gzip.decompress(data)
    except (gzip.BadGzipFile, EOFError, zlib.error) as e:
        raise InputError(f"{path}: not a valid gzip file ({e})") from None


def read_instance(path: str | os.PathLike[str]) -> Instance:
    """Read an instance from a ``.json`` (UAV) or ``.gtsp`` (GTSPLIB) file, either maybe ``.gz``.

    Raises
    ------
    InputError
        ``"<path>: <problem>"`` for a missing, unreadable or malformed file (a bad gzip file too).
    """
    p = Path(path)
    suffix = _instance_suffix(p)
    text = _read_text(p)
    try:
        if suffix == ".gtsp":
            return parse_gtsp(text)
        return parse_json_instance(text, default_name=instance_stem(p))
    except InputError as e:
        raise InputError(f"{p}: {e}") from None


def read_solution(path: str | os.PathLike[str]) -> tuple[list[int], list[int]]:
    """Read ``(order, heads)`` from a solution JSON file (the shape ``solve --json`` prints)."""
    p = Path(path)
    try:
        return parse_solution(_read_text(p))
    except InputError as e:
        if str(e).startswith(f"{p}:"):
            raise
        raise InputError(f"{p}: {e}") from None


def read_tour(path: str | os.PathLike[str], instance: Instance) -> tuple[list[int], list[int]]:
    """Read a TSPLIB tour file (``.tour`` or ``.tour.gz``) of ``instance`` as ``(order, heads)``.

    ``instance`` is the instance the tour's node ids refer to (for a GTSPLIB tour: the instance
    read from that file); :func:`gtsp_bench.data.parse.tour_node_ids` says how ids name nodes.
    """
    p = Path(path)
    try:
        return tour_to_solution(instance, parse_tour(_read_text(p)))
    except InputError as e:
        if str(e).startswith(f"{p}:"):
            raise
        raise InputError(f"{p}: {e}") from None


def read_solution_file(path: str | os.PathLike[str], instance: Instance) -> tuple[list[int], list[int]]:
    """Read a feasible solution of ``instance`` as ``(order, heads)`` from a TSPLIB tour file
    (a name ending in ``.tour`` or ``.tour.gz``) or a solution JSON file (any other name).

    Raises
    ------
    InputError
        ``"<path>: <problem>"`` for a file that cannot be read, and
        ``"<path>: infeasible solution: <problem>"`` for a solution that is not one of
        ``instance`` (a cluster missed or visited twice, a head out of range).
    """
    p = Path(path)
    order, heads = read_tour(p, instance) if format_suffix(p) == TOUR_SUFFIX else read_solution(p)
    try:
        instance.check_solution(order, heads)
    except InfeasibleSolutionError as e:
        raise InputError(f"{p}: infeasible solution: {e}") from None
    return order, heads


def check_tour_name(path: str | os.PathLike[str]) -> Path:
    """``path`` as a :class:`~pathlib.Path` when it names a tour file (``.tour``, ``.tour.gz``).

    Raises
    ------
    InputError
        ``"<path>: a tour file's name ends in .tour ..."`` otherwise: only such a name is read
        back as a tour (:func:`read_solution_file`).
    """
    p = Path(path)
    if format_suffix(p) != TOUR_SUFFIX:
        raise InputError(f"{p}: a tour file's name ends in {TOUR_SUFFIX} (or {TOUR_SUFFIX}{GZIP_SUFFIX})")
    return p


def write_tour(instance: Instance, path: str | os.PathLike[str], order: Sequence[int],
               heads: Sequence[int], comments: Sequence[str] = ()) -> Path:
    """Write a solution of ``instance`` atomically as a TSPLIB tour file (``.tour``, or gzip-
    compressed ``.tour.gz``): :func:`gtsp_bench.data.parse.format_tour`, with ``COMMENT`` lines.

    Raises
    ------
    InputError
        For a name that does not end in ``.tour`` or ``.tour.gz``, a folder that cannot be
        written, or a solution that is not one of ``instance``.
    """
    p = check_tour_name(path)
    _write_text(p, format_tour(instance, order, heads, comments))
    return p


def write_instance(instance: Instance, path: str | os.PathLike[str]) -> Path:
    """Write an instance atomically, as JSON or GTSPLIB by the file suffix; gzip-compressed when
    the name ends in ``.gz`` (reproducibly: no name or time stamp in the gzip header)."""
    p = Path(path)
    suffix = _instance_suffix(p)
    _write_text(p, format_gtsp(instance) if suffix == ".gtsp" else format_json_instance(instance))
    return p


def _write_text(p: Path, text: str) -> None:
    """Write ``text`` atomically; gzip-compressed when the name ends in ``.gz`` (reproducibly)."""
    if p.suffix.lower() == GZIP_SUFFIX:
        atomic_write_bytes(p, gzip.compress(text.encode("utf-8"), mtime=0))
    else:
        atomic_write_text(p, text)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` so that readers see the old file or the whole new one."""
    atomic_write_bytes(path, text.encode("utf-8"))


def csv_text(table: Any) -> str:
    """A pandas table as the suite writes every CSV: no index, floats to 10 significant digits."""
    return str(table.to_csv(index=False, float_format="%.10g"))


def atomic_write_csv(path: str | os.PathLike[str], table: Any) -> None:
    """Write a pandas table as :func:`csv_text` atomically (:func:`atomic_write_text`)."""
    atomic_write_text(path, csv_text(table))


def atomic_write_json(path: str | os.PathLike[str], data: Any) -> None:
    """Write ``data`` as indented JSON with a final newline, atomically (a run's manifest)."""
    atomic_write_text(path, json.dumps(data, indent=1) + "\n")


def _create_temp(folder: Path, name: str) -> tuple[int, str]:
    """A new, uniquely named file beside ``name`` opened for writing, created with mode 0o666 so
    that the kernel applies the umask (as an ordinary ``open(path, "w")`` would); the process umask
    is never read or changed."""
    for _ in range(100):
        tmp = str(folder / f".{name}.{secrets.token_hex(6)}.tmp")
        try:
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0),
                           0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name beside {name}")


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder and a rename.

    The file gets the permissions of an ordinary write (a new file: 0o666 less the umask, applied
    by the kernel; an existing file keeps its own), and the process umask is left alone.

    Raises
    ------
    InputError
        ``"<path>: cannot write (<reason>)"`` when the folder or the file cannot be written (a
        read-only folder, a directory of that name, a full disk, ...).
    """
    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = _create_temp(p.parent, p.name)
    except OSError as e:
        raise InputError(f"{p}: cannot write ({e.strerror})") from None
    try:
        mode = p.stat().st_mode & 0o7777 if p.is_file() else None
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            if mode is not None:
                os.fchmod(f.fileno(), mode)
            os.fsync(f.fileno())
        os.replace(tmp, p)
    except OSError as e:
        Path(tmp).unlink(missing_ok=True)
        raise InputError(f"{p}: cannot write ({e.strerror})") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
