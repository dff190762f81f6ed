"""Keep numba's on-disk cache of the lns kernels in step with their sources.

numba (``cache=True``) keys each cached kernel on its own file only: a kernel that calls a
compiled function imported from another file keeps the callee's old code after that file is
edited (numba's documentation, "Cache invalidation fails to recognize changes in functions defined
in a different file"). The lns kernels span four files (:data:`KERNEL_SOURCES`), so an edit to
one of them could leave the others' cached kernels running the old code, silently. This module
keeps one digest of all four next to numba's cache files (``__pycache__``) and deletes the
folder's cached kernels when the digest changes; numba then compiles them again.

A fresh clone or an installed package has no stale cache, and a folder numba cannot write to
(where it caches elsewhere, e.g. under ``NUMBA_CACHE_DIR``) is left alone: the guard is for a
working copy being edited.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

#: The files whose compiled functions call each other (in import order).
KERNEL_SOURCES = ("lns_costs.py", "lns_local.py", "lns_window.py", "lns_kernels.py")
#: The digest's file name in the ``__pycache__`` folder.
DIGEST_NAME = "lns-kernels.sha256"
#: numba's cache files: an index and the compiled code of each kernel.
CACHE_SUFFIXES = (".nbi", ".nbc")


def sources_digest(folder: Path, names: tuple[str, ...] = KERNEL_SOURCES) -> str:
    """SHA-256 of the named files' bytes, in order (a missing file counts as empty)."""
    h = hashlib.sha256()
    for name in names:
        path = folder / name
        h.update(name.encode())
        h.update(path.read_bytes() if path.is_file() else b"")
    return h.hexdigest()


def clear_stale(folder: Path, names: tuple[str, ...] = KERNEL_SOURCES) -> bool:
    """Delete the cached kernels of ``folder``'s ``names`` when the sources differ from the last
    recorded digest (or none was recorded); returns whether any file was deleted.

    Never raises for the file system: an unreadable or read-only folder is left as it is.
    """
    cache = folder / "__pycache__"
    stamp = cache / DIGEST_NAME
    try:
        digest = sources_digest(folder, names)
        if stamp.is_file() and stamp.read_text().strip() == digest:
            return False
        stems = tuple(Path(name).stem + "." for name in names)
        stale = [p for p in cache.glob("*") if p.suffix in CACHE_SUFFIXES and p.name.startswith(stems)] \
            if cache.is_dir() else []
        for path in stale:
            path.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        tmp = stamp.with_name(f"{DIGEST_NAME}.{os.getpid()}.tmp")  # one per process
        tmp.write_text(digest + "\n")
        tmp.replace(stamp)
    except OSError:
        return False
    return bool(stale)
