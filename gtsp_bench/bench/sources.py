"""A benchmark's instances: its sources (:mod:`gtsp_bench.bench.definitions`) read into entries.

An :class:`Entry` is one instance as the engine solves it: the set it belongs to (the group rows
and summaries carry), its file's text and hash (task keys, the manifest), the reference rows its
set holds and, for a budget relative to GLNS's time, that time. Generated sets are written once
into ``instances/uav-K{K}-N{N}-s{seed}/`` and re-used (:func:`load_generated`, the paper runner's
rule: a file with other generator settings is an error, never overwritten).
"""

from __future__ import annotations

import csv
import functools
import hashlib
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from gtsp_bench.bench.definitions import Committed, Generated, Gtsplib, Source
from gtsp_bench.bench.tasks import StoredInstance, fingerprint
from gtsp_bench.data.sets import (
    ReferenceRow,
    SetFile,
    gtsplib_reference_row,
    read_reference,
    read_set_file,
    resolve_set,
)
from gtsp_bench.errors import InputError

if TYPE_CHECKING:
    from gtsp_bench.data.gtsplib import Reference

#: Where a committed set's generated files live: ``instances/uav-K{K}-N{N}-s{seed}``.
GENERATED_SET = "uav-K{k}-N{n}-s{seed}"


@dataclass(frozen=True)
class Entry:
    """One instance of a benchmark.

    ``set`` names its group (a set folder, or a GTSPLIB size group); ``references`` are its set's
    rows by omega (``None`` for a distance-only instance); ``glns_s``: GLNS's C++ mean seconds on
    it, where ``glns-45.csv`` has them.
    """

    set: str
    stem: str
    stored: StoredInstance
    references: Mapping[float | None, ReferenceRow] = field(default_factory=dict)
    glns_s: float | None = None

    @property
    def k(self) -> int:
        """Clusters."""
        return self.stored.instance.n_clusters

    @property
    def n(self) -> int:
        """Nodes per cluster (a UAV instance's first cluster), else all nodes."""
        inst = self.stored.instance
        return int(inst.sizes[0]) if inst.is_uav else inst.n_nodes

    @functools.cached_property
    def sha256(self) -> str:
        """The SHA-256 of the instance file's (uncompressed) text."""
        return hashlib.sha256(self.stored.text.encode()).hexdigest()


def load_generated(instance_dir: Path, k: int, n: int, seed: int, nodes: int) -> list[StoredInstance]:
    """The first ``n`` instances of the seeded set for K = ``k``, written once and re-used.

    A file present with other generator settings than asked is an error (it is never
    overwritten); one whose coordinates differ from what the generator gives now is used, with a
    warning.
    """
    from gtsp_bench.data.io import atomic_write_text, read_instance
    from gtsp_bench.data.parse import format_json_instance
    from gtsp_bench.generator import instance_set

    folder = instance_dir / GENERATED_SET.format(k=k, n=nodes, seed=seed)
    out = []
    for fresh in instance_set(n, k, seed, nodes):
        path = folder / f"{fresh.name}.json"
        fresh_text = format_json_instance(fresh)
        if path.exists():
            inst = read_instance(path)
            text = path.read_text(encoding="utf-8")
            want = dict(fresh.meta["generator"])
            have = dict(inst.meta.get("generator", {}))
            if have != want:
                raise InputError(
                    f"{path}: its generator settings {have} are not {want}; move it away to regenerate it"
                )
            if text != fresh_text:
                print(
                    f"gtsp-bench: warning: {path} differs from what the generator gives now; using the file",
                    file=sys.stderr,
                )
        else:
            atomic_write_text(path, fresh_text)
            inst, text = fresh, fresh_text
        out.append(StoredInstance(inst, text, fingerprint(text), path))
    return out


def _by_omega(
    rows: Mapping[tuple[str, float | None], ReferenceRow], stem: str
) -> dict[float | None, ReferenceRow]:
    return {w: r for (s, w), r in rows.items() if s == stem}


def _generated(src: Generated, instance_dir: Path, scratch: Path) -> list[Entry]:
    out = []
    for k in src.ks:
        name = GENERATED_SET.format(k=k, n=src.nodes, seed=src.seed)
        where = instance_dir if (instance_dir / name).is_dir() else scratch
        stored = load_generated(where, k, src.instances, src.seed, src.nodes)
        refs = read_reference(where / name / "reference.csv")
        out += [Entry(name, s.path.stem, s, _by_omega(refs, s.path.stem)) for s in stored]
    return out


def _committed(src: Committed, instance_dir: Path) -> list[Entry]:
    out = []
    for name in src.sets:
        s = resolve_set(name, instance_dir)
        files = s.files if src.instances is None else s.files[: src.instances]
        for f in files:
            inst, text, digest = read_set_file(f)
            out.append(
                Entry(
                    s.name,
                    f.stem,
                    StoredInstance(inst, text, digest, f.path),
                    _by_omega(s.references, f.stem),
                )
            )
    return out


def glns_times() -> dict[str, float]:
    """GLNS's C++ mean seconds per instance (``instances/gtsplib/glns-45.csv``)."""
    from gtsp_bench.data import gtsplib

    path = gtsplib.folder() / "glns-45.csv"
    try:
        with path.open(newline="") as f:
            return {r["instance"]: float(r["glns_cpp_mean_s"]) for r in csv.DictReader(f)}
    except (OSError, KeyError, ValueError) as e:
        raise InputError(f"{path}: cannot read GLNS's times ({e})") from None


def gtsplib_references(src: Gtsplib) -> list[tuple[str, Reference]]:
    """The files ``src`` picks, each with its group label and its ``best_known.csv`` row, in
    the table's order (or ``src.names``')."""
    from gtsp_bench.data import gtsplib

    table = gtsplib.best_known()
    refs = list(table.values())
    if src.names:
        missing = [n for n in src.names if n not in table]
        if missing:
            raise InputError(f"no GTSPLIB instance {missing[0]!r}")
        picked = [("gtsplib", table[n]) for n in src.names]
    else:
        if src.group == "glns-45":
            refs = [table[n] for n in glns_times()]
        elif src.group == "samples":
            from gtsp_bench.bench.definitions import SAMPLES

            refs = [table[n] for n in SAMPLES]
        hi = src.max_nodes or 10**9
        refs = [
            r
            for r in refs
            if src.min_nodes <= r.nodes <= hi
            and (r.symmetric or not src.symmetric_only)
            and not (src.asymmetric_only and r.symmetric)
        ]
        if src.size_groups:
            picked = []
            for label, lo, top in src.size_groups:
                mine = [r for r in refs if lo <= r.nodes <= top]
                picked += [(label, r) for r in mine[: src.per_group]]
        else:
            picked = [("gtsplib", r) for r in refs]
    return picked


def _gtsplib(src: Gtsplib) -> list[Entry]:
    from gtsp_bench.data import gtsplib

    glns = glns_times()
    out = []
    for label, r in gtsplib_references(src):
        path = gtsplib.path(r.name)
        inst, text, digest = read_set_file(SetFile(path, r.name))
        out.append(Entry(label, r.name, StoredInstance(inst, text, digest, path),
                         {None: gtsplib_reference_row(r)}, glns.get(r.name)))
    return out


def best_known_tour(e: Entry) -> tuple[tuple[tuple[int, ...], tuple[int, ...]], str]:
    """The best-known tour of a GTSPLIB entry in the library it was read from (the
    ``best_known.csv`` beside its file), as a warm start ``(order, heads)``, and the name of its
    tour file (which changes when a shorter tour is kept).

    Raises
    ------
    InputError
        ``FILE: problem``: no ``best_known.csv`` beside the file names it (UAV sets keep values,
        not tours), or its tour file cannot be read.
    """
    from gtsp_bench.data import gtsplib
    from gtsp_bench.data.io import read_tour

    where = e.stored.path.parent
    ref = gtsplib.read_best_known(where).get(e.stem) if (where / "best_known.csv").is_file() else None
    if ref is None:
        raise InputError(f"{e.stored.path}: initial=best-known starts from the tour of a GTSPLIB file "
                         "that its folder's best_known.csv names; this file has none")
    order, heads = read_tour(where / ref.tour, e.stored.instance)
    return (tuple(order), tuple(heads)), ref.tour


def load_sources(
    sources: Sequence[Source],
    instance_dir: Path,
    *,
    ks: Sequence[int] | None = None,
    names: Sequence[str] | None = None,
    scratch: Path | None = None,
) -> list[Entry]:
    """Every entry of ``sources``, in order (an instance named twice is kept once). ``ks`` sets the
    cluster counts of the generated sets and keeps only the other sources' instances of that many
    clusters; ``names`` keeps the instances of those file stems.

    A generated set whose folder is committed under ``instance_dir`` is read (and completed)
    there; any other is written into ``scratch`` (a run's ``OUT/instances``), so that a benchmark
    never adds folders to the committed ones.

    Raises
    ------
    InputError
        A bad set or file, a name no source holds, or nothing left after the selection.
    """
    out: list[Entry] = []
    seen: set[tuple[str, str]] = set()
    for src in sources:
        if isinstance(src, Generated):
            if ks is not None:  # -K sets the generated sets' cluster counts
                src = Generated(tuple(ks), src.instances, src.seed, src.nodes)
            got = _generated(src, instance_dir, scratch or instance_dir)
        elif isinstance(src, Committed):
            got = _committed(src, instance_dir)
        else:
            got = _gtsplib(src)
        for e in got:
            if (e.set, e.stem) in seen:
                continue
            if (ks is not None and e.k not in ks) or (names and e.stem not in names):
                continue
            seen.add((e.set, e.stem))
            out.append(e)
    if names:
        missing = [n for n in names if n not in {e.stem for e in out}]
        if missing:
            raise InputError(f"--names: no instance {missing[0]!r} in this benchmark's sources")
    if not out:
        raise InputError("no instance left after the selection (-K, --names)")
    return out


__all__ = ["GENERATED_SET", "Entry", "glns_times", "load_generated", "load_sources"]
