"""The lns kernels' cache guard: stale numba cache files go when any kernel source changes."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest
from gtsp_bench.solvers.heuristics import kernel_cache
from gtsp_bench.solvers.heuristics.kernel_cache import DIGEST_NAME, clear_stale, sources_digest

NAMES = ("a.py", "b.py")


def _tree(tmp_path: Path) -> Path:
    for name in NAMES:
        (tmp_path / name).write_text(f"# {name}\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    for name in ("a.f-10.py311.nbi", "a.f-10.py311.1.nbc", "b.g-3.py311.nbi", "other.h-1.py311.nbi",
                 "a.cpython-311.pyc"):
        (cache / name).write_bytes(b"x")
    return tmp_path


def _cached(folder: Path) -> set[str]:
    return {p.name for p in (folder / "__pycache__").iterdir()}


def test_first_call_clears_unrecorded_caches_and_records_the_digest(tmp_path):
    """With no digest recorded, the named modules' numba files go (of unknown sources)."""
    folder = _tree(tmp_path)
    assert clear_stale(folder, NAMES) is True
    # the named modules' numba files go; another module's and Python's bytecode stay
    assert _cached(folder) == {"other.h-1.py311.nbi", "a.cpython-311.pyc", DIGEST_NAME}
    assert (folder / "__pycache__" / DIGEST_NAME).read_text().strip() == sources_digest(folder, NAMES)


def test_unchanged_sources_keep_the_cache(tmp_path):
    """A second call with the same sources deletes nothing."""
    folder = _tree(tmp_path)
    clear_stale(folder, NAMES)
    (folder / "__pycache__" / "b.g-3.py311.nbi").write_bytes(b"new")  # compiled again since
    assert clear_stale(folder, NAMES) is False
    assert "b.g-3.py311.nbi" in _cached(folder)


def test_an_edit_to_any_source_clears_every_named_module(tmp_path):
    """Editing one file clears the cached kernels of all the named files."""
    folder = _tree(tmp_path)
    clear_stale(folder, NAMES)
    for name in ("a.f-10.py311.nbi", "b.g-3.py311.nbi"):
        (folder / "__pycache__" / name).write_bytes(b"new")
    (folder / "b.py").write_text("# b, edited\n")  # only b changed: a's kernels may call b's
    assert clear_stale(folder, NAMES) is True
    assert "a.f-10.py311.nbi" not in _cached(folder) and "b.g-3.py311.nbi" not in _cached(folder)
    assert clear_stale(folder, NAMES) is False


def test_digest_depends_on_content_and_order(tmp_path):
    """The digest changes with a file's bytes and with the files' order."""
    folder = _tree(tmp_path)
    one = sources_digest(folder, NAMES)
    assert sources_digest(folder, NAMES[::-1]) != one
    (folder / "a.py").write_text("# a, edited\n")
    assert sources_digest(folder, NAMES) != one


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes anywhere")
def test_read_only_folder_is_left_alone(tmp_path):
    """A cache folder that cannot be written is left as it is, without an error."""
    folder = _tree(tmp_path)
    cache = folder / "__pycache__"
    cache.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        assert clear_stale(folder, NAMES) is False
    finally:
        cache.chmod(stat.S_IRWXU)


def test_file_system_errors_never_raise(tmp_path, monkeypatch):
    """An OS error while deleting is swallowed (an import must never fail for the cache)."""
    folder = _tree(tmp_path)

    def refuse(*args, **kwargs):
        raise PermissionError("read-only")

    monkeypatch.setattr(Path, "unlink", refuse)
    assert clear_stale(folder, NAMES) is False


def test_the_package_guards_its_own_kernel_files():
    """The guarded names are the package's kernel files, and importing it recorded their digest."""
    folder = Path(kernel_cache.__file__).parent
    assert all((folder / name).is_file() for name in kernel_cache.KERNEL_SOURCES)
    recorded = folder / "__pycache__" / DIGEST_NAME
    if recorded.is_file():  # written on import unless the folder is read-only
        assert recorded.read_text().strip() == sources_digest(folder)
