"""The runner's task log: one JSON record per finished solve, appended durably, read back with
every record checked, and the rules for which logged solves a run redoes; and the lock that keeps
two runs out of one output folder."""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from gtsp_bench.errors import InputError


class TaskLog:
    """Finished tasks, one JSON object per line, appended with flush and fsync.

    Reading drops a torn last line (a run killed mid-write), checks every record against the log's
    schema (:func:`gtsp_bench.checks.check_log_record`) and keeps the last good record of a key. A
    line that is not JSON or fails the check is skipped, and :attr:`skipped` says which and why
    (``"<log>:<line>: <reason>"``), so its solve is redone rather than trusted.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self._file: io.TextIOWrapper | None = None
        self._checked_end = False
        self.skipped: list[str] = []

    def load(self, sizes: Mapping[str, Sequence[int]] | None = None) -> dict[str, dict[str, Any]]:
        """Records by key; cuts a torn last line off the file.

        Parameters
        ----------
        sizes
            Cluster sizes of the instance of each key the caller knows: those records' ``order``
            and ``heads`` are checked against them.
        """
        from gtsp_bench.checks import check_log_record

        self.skipped = []
        if not self.path.exists():
            return {}
        try:
            data = self.path.read_bytes()
        except OSError as e:
            raise InputError(f"{self.path}: cannot read ({e.strerror})") from None
        end = data.rfind(b"\n") + 1
        if end < len(data):
            with open(self.path, "r+b") as f:
                f.truncate(end)
        records = {}
        sizes = sizes or {}
        for number, line in enumerate(data[:end].split(b"\n")[:-1], start=1):
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except (ValueError, RecursionError):
                self.skipped.append(f"{self.path}:{number}: not a JSON record")
                continue
            try:
                key = rec.get("key") if isinstance(rec, dict) else None
                check_log_record(rec, sizes.get(key) if isinstance(key, str) else None)
            except InputError as e:
                self.skipped.append(f"{self.path}:{number}: {e}")
                continue
            records[rec["key"]] = rec
        return records

    def open(self) -> None:
        """Open the log for appending, creating its folder.

        Raises
        ------
        InputError
            ``"<path>: cannot write (<reason>)"`` when the folder or the file cannot be made.
        """
        if self._file is None:
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._file = open(self.path, "a", encoding="utf-8")  # noqa: SIM115 (closed in close())
                self._checked_end = False
            except OSError as e:
                raise InputError(f"{self.path}: cannot write ({e.strerror})") from None

    def append(self, record: Mapping[str, Any]) -> None:
        """Append one record durably."""
        self.open()
        assert self._file is not None
        line = json.dumps(record, allow_nan=True) + "\n"
        if not self._checked_end:  # a torn last line that load() did not cut: never glue onto it
            self._checked_end = True
            if self._file.tell() > 0 and not _ends_with_newline(self.path):
                line = "\n" + line
        self._file.write(line)
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        """Close the file (appending reopens it)."""
        if self._file is not None:
            self._file.close()
            self._file = None


def _ends_with_newline(path: Path) -> bool:
    with open(path, "rb") as f:
        f.seek(-1, os.SEEK_END)
        return f.read(1) == b"\n"


@contextlib.contextmanager
def exclusive_lock(path: Path, holder: str) -> Iterator[Path]:
    """Hold an exclusive lock on the file ``path`` (made if missing) for the ``with`` block.

    The lock is an ``flock`` the kernel drops when its process ends, however it ends, so a run
    killed with SIGKILL leaves no stale lock behind. The file holds the holder's process id.

    Raises
    ------
    InputError
        At once, ``"<path>: locked by <holder> (process <pid>) ..."`` when another process holds
        it, or ``"<path>: cannot write (...)"``.
    """
    import fcntl

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as e:
        raise InputError(f"{path}: cannot write ({e.strerror})") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            raise InputError(f"{path}: locked by {holder} (process {pid}) using the same folder; "
                             f"wait for it to finish or choose another output folder") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield path
    finally:
        os.close(fd)  # releases the lock


def has_answer(record: Mapping[str, Any]) -> bool:
    """Whether a record holds a solution (a finite objective)."""
    return record.get("objective") is not None and math.isfinite(record["objective"])


def failure_cause(record: Mapping[str, Any]) -> str | None:
    """Whose fault a failed record was: its ``cause``, or for records written before causes were
    logged, ``"infrastructure"`` when its note says its worker died or memory ran out."""
    if record.get("status") != "failed":
        return None
    if "cause" in record:
        return str(record["cause"])
    note = str(record.get("note", ""))
    outside = note.startswith(("worker died", "MemoryError", "out of memory"))
    return "infrastructure" if outside else "solver"


def needs_run(record: Mapping[str, Any] | None, retry_failed: bool) -> bool:
    """Whether a task with this log record (``None``: none) is solved (again) by this run: when
    it has no record, failed for a cause outside the solver, or failed at all with
    ``retry_failed``."""
    if record is None:
        return True
    cause = failure_cause(record)
    return cause == "infrastructure" or (cause is not None and retry_failed)
