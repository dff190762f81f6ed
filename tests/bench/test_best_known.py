"""New best-known GTSPLIB tours: kept only with --update-reference, into the library the rows were
read from, named by their finder; never below a proven optimum; the hint of a run without it."""

from __future__ import annotations

import hashlib
import math
from dataclasses import replace

import pandas as pd
import pytest

from gtsp_bench.bench.best_known import finder, keep_best_known, keep_hint, libraries
from gtsp_bench.bench.definitions import BENCHMARKS
from gtsp_bench.bench.output_kinds import OUTPUTS
from gtsp_bench.errors import InputError
from tests.bench.frames import row_frame as _rows


def _gtsplib_rows(tmp_path, value: int) -> tuple[pd.DataFrame, object]:
    """A copy of the library with 11berlin52 as a best_known row of ``value``, and two rows: GLKH's
    tour (4040) and a longer one, each of the library's file."""
    from gtsp_bench.data import gtsplib
    from gtsp_bench.data.io import read_text
    from tests.conftest import GTSPLIB

    ref = replace(gtsplib.best_known()["11berlin52"], status="best_known", value=value, published=value)
    (tmp_path / "best_known.csv").write_text(gtsplib.format_best_known([ref]))
    (tmp_path / "11berlin52.gtsp.gz").write_bytes((GTSPLIB / "11berlin52.gtsp.gz").read_bytes())
    sha = hashlib.sha256(read_text(tmp_path / "11berlin52.gtsp.gz").encode()).hexdigest()
    order, heads = gtsplib.best_tour("11berlin52")
    text = {"order": " ".join(map(str, order)), "heads": " ".join(map(str, heads))}
    df = pd.concat([_rows(instance="11berlin52", instance_sha256=sha, objective=4040.0, seed=3, **text),
                    _rows(instance="11berlin52", instance_sha256=sha, objective=4100.0, seed=4,
                          order=" ".join(map(str, range(11))), heads=" ".join(["0"] * 11))])
    return df, gtsplib


def test_best_known_keeps_the_shortest_tour_below_the_library_value(tmp_path):
    """The shortest tour below the row's value is kept with the run's label, budget and seed as
    its source; rows of another file of the same name, or not below the value, change nothing."""
    df, gtsplib = _gtsplib_rows(tmp_path, 4100)
    assert keep_best_known(df.assign(instance_sha256="0" * 64), tmp_path, "2026-11-27") == []
    assert keep_best_known(df, tmp_path, "2026-11-27") == [
        ("11berlin52", 4100.0, 4040.0, "gtsp-bench lns 1s seed 3")]
    row = gtsplib.parse_best_known((tmp_path / "best_known.csv").read_text())["11berlin52"]
    assert (row.value, row.tour, row.date) == (4040.0, "tours/11berlin52.4040.tour.gz", "2026-11-27")
    assert keep_best_known(df, tmp_path, "2026-11-28") == []


def test_rows_without_a_tour_are_passed_over(tmp_path):
    """A row below the value whose tour was not kept (no order) cannot be kept: nothing written."""
    df, _ = _gtsplib_rows(tmp_path, 4100)
    for order in (math.nan, "", " "):
        assert keep_best_known(df.assign(order=order), tmp_path, "2026-11-27") == []
    assert not (tmp_path / "tours").exists()


def test_best_known_output_keeps_tours_only_when_asked(tmp_path, monkeypatch):
    """Without --update-reference the output writes nothing, even for a checkout's results/NAME;
    with it the tour goes into the library the run read ($GTSP_BENCH_GTSPLIB here), whatever
    the output folder, its source naming the solver, the run's options, budget and seed."""
    from types import SimpleNamespace

    df, gtsplib = _gtsplib_rows(tmp_path, 4100)
    monkeypatch.setenv(gtsplib.ENV_VAR, str(tmp_path))
    bench = BENCHMARKS["glns"]
    said: list[str] = []
    (tmp_path / "mkdocs.yml").write_text("site_name: x\n")
    for settings in (None, SimpleNamespace(update_reference=False)):
        assert OUTPUTS["best-known"](bench, df, tmp_path / "results" / "glns", settings, said.append) == []
    assert not (tmp_path / "tours").exists() and said == []
    asked = SimpleNamespace(update_reference=True)
    written = OUTPUTS["best-known"](bench, df, tmp_path / "elsewhere", asked, said.append)
    assert written == [tmp_path / "best_known.csv"]
    source = "gtsp-bench lns effort=budget 1s seed 3"
    assert said == [f"new best known: 11berlin52: 4100 -> 4040 ({source}), tour in {tmp_path / 'tours'}"]
    row = gtsplib.parse_best_known((tmp_path / "best_known.csv").read_text())["11berlin52"]
    assert (row.value, row.published, row.source) == (4040, 4100, source)
    assert (tmp_path / "tours" / "11berlin52.4040.tour.gz").is_file()


def test_best_known_output_fails_loudly_below_a_proven_optimum(tmp_path, monkeypatch):
    """A tour below an optimal row is never kept: an InputError naming the table, nothing written."""
    df, gtsplib = _gtsplib_rows(tmp_path, 4100)
    ref = gtsplib.parse_best_known((tmp_path / "best_known.csv").read_text())["11berlin52"]
    (tmp_path / "best_known.csv").write_text(gtsplib.format_best_known([replace(ref, status="optimal")]))
    with pytest.raises(InputError, match=r"best_known.csv: 11berlin52: .* below the proven optimum 4100"):
        keep_best_known(df, tmp_path, "2026-11-28")
    assert not (tmp_path / "tours").exists()


def test_finder_names_solver_options_budget_and_seed():
    """The source of a kept tour: the run's options from the definition by the row's label; a
    label the definition lacks (or no definition) gives the solver alone."""
    row = _rows(label="lns", solver="lns", time_limit=300.0, seed=2).iloc[0]
    assert finder(BENCHMARKS["glns-large"], row) == "gtsp-bench lns effort=budget 300s seed 2"
    assert finder(None, row) == "gtsp-bench lns 300s seed 2"
    assert finder(None, _rows(time_limit=math.nan).iloc[0]) == "gtsp-bench lns seed 0"


def test_keep_hint_counts_solves_and_files_and_names_the_command():
    """The hint of a run without --update-reference: solves, files and the command to rerun."""
    better = pd.concat([_rows(instance="a", seed=1), _rows(instance="a", seed=2), _rows(instance="b")])
    hint = keep_hint(better, "gtsp-bench bench glns-large --seeds 1,2")
    assert hint.startswith("3 solve(s) of 2 file(s) went below the best-known value; "
                           "`gtsp-bench bench glns-large --seeds 1,2 --update-reference` keeps their tours")
    assert "the same command with --update-reference" in keep_hint(better, "")


def test_rows_of_a_library_copy_go_to_that_copy(tmp_path, monkeypatch):
    """A --set folder read as GTSPLIB (a copy with best_known.csv) takes its own rows; the rest go
    to the library; a bad --set is passed over."""
    from types import SimpleNamespace

    from gtsp_bench.data import gtsplib

    (tmp_path / "copy").mkdir()
    df, _ = _gtsplib_rows(tmp_path / "copy", 4100)
    df = pd.concat([df.assign(set="copy"), df.assign(set="gtsplib")])
    settings = SimpleNamespace(sets=(str(tmp_path / "copy"), str(tmp_path / "nothing")),
                               instance_dir=tmp_path)
    got = libraries(df, settings)
    assert sorted(got) == sorted([(tmp_path / "copy").resolve(), gtsplib.folder().resolve()])
    assert set(got[(tmp_path / "copy").resolve()]["set"]) == {"copy"}
    monkeypatch.setenv(gtsplib.ENV_VAR, str(tmp_path / "absent"))
    assert list(libraries(df, settings)) == [(tmp_path / "copy").resolve()]


def test_keep_hint_drops_fresh_so_the_rerun_reuses_the_solves():
    """A run made with --fresh is told to rerun without it: --fresh would solve everything again."""
    better = pd.DataFrame({"instance": ["464u2319"]})
    hint = keep_hint(better, "gtsp-bench bench glns-large --seeds 1 --fresh --no-progress")
    assert "`gtsp-bench bench glns-large --seeds 1 --no-progress --update-reference`" in hint
    assert "--fresh" not in hint
