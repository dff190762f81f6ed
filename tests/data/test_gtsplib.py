"""The bundled GTSPLIB (instances/gtsplib/): GLKH's best tours priced by the one evaluator, the
reference table, and the by-name helpers of gtsp_bench.data.gtsplib.

Every instance of the library (143, 14 to 85,900 nodes: 124 symmetric and the 19 asymmetric
``AGTSP`` ones) is read and GLKH's best tour of it priced with :func:`gtsp_bench.energy.evaluate`;
the length must equal the published best-known value exactly. This checks the reader (every
header variant, edge-weight type and explicit format that occurs), every distance rule against an
independent implementation, and that an asymmetric tour is priced in the direction the tour file
lists it. The instances above :data:`LARGE` nodes carry the ``large_gtsplib`` marker (about 10 s
together); ``make test`` runs them, ``-m 'not large_gtsplib'`` leaves them out.
"""

from __future__ import annotations

import csv
import re
import subprocess
import sys
from dataclasses import replace

import pytest

from gtsp_bench.data import gtsplib
from gtsp_bench.data.io import read_instance, read_tour
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from tests.conftest import GTSPLIB

with (GTSPLIB / "best_known.csv").open() as _f:
    ROWS = list(csv.DictReader(_f))
ASYMMETRIC = [r for r in ROWS if r["type"] == "AGTSP"]
#: Instances with more nodes than this are marked ``large_gtsplib``.
LARGE = 10_000


def _param(row: dict[str, str]):
    marks = [pytest.mark.large_gtsplib] if int(row["nodes"]) > LARGE else []
    return pytest.param(row, id=row["name"], marks=marks)


def test_the_library_is_complete():
    """143 instances, each with its file and its best-known tour; besides them only tours a
    shorter one superseded (NAME.LENGTH.tour.gz, longer than the row's value)."""
    assert len(ROWS) == 143 and len(ASYMMETRIC) == 19
    files = {p.name for p in GTSPLIB.glob("*.gtsp.gz")}
    assert files == {f"{r['name']}.gtsp.gz" for r in ROWS}
    tours = {f"tours/{p.name}" for p in (GTSPLIB / "tours").iterdir()}
    assert tours >= {r["tour"] for r in ROWS}
    for r in ROWS:  # the tour file's name carries its length: NAME.LENGTH.tour.gz
        assert r["tour"] == f"tours/{r['name']}.{r['best_known']}.tour.gz"
    by_name = {r["name"]: float(r["best_known"]) for r in ROWS}
    for t in tours - {r["tour"] for r in ROWS}:
        name, length = t.removeprefix("tours/").removesuffix(".tour.gz").rsplit(".", 1)
        assert float(length) > by_name[name], t


def test_published_values_stay_findable():
    """Every row has its published (GLKH's) value: the row's own where GLKH's tour is the best
    known, else above it, with GLKH's tour file still in tours/ under that length."""
    for r in ROWS:
        if r["source"] == "GLKH":
            assert r["published"] == r["best_known"], r["name"]
        else:
            assert float(r["published"]) > float(r["best_known"]), r["name"]
            assert (GTSPLIB / "tours" / f"{r['name']}.{r['published']}.tour.gz").is_file(), r["name"]


_SUPERSEDED = sorted(
    p.name for p in (GTSPLIB / "tours").iterdir() if f"tours/{p.name}" not in {r["tour"] for r in ROWS}
)


@pytest.mark.parametrize("file", _SUPERSEDED or [pytest.param("", marks=pytest.mark.skip("none kept yet"))])
def test_superseded_tours_price_to_the_length_they_are_named_for(file):
    """A tour a shorter one superseded (GLKH's published one, or an earlier kept one) still prices
    to the LENGTH of its name NAME.LENGTH.tour.gz: every value the table ever held has its tour."""
    name, length = file.removesuffix(".tour.gz").rsplit(".", 1)
    inst = read_instance(GTSPLIB / f"{name}.gtsp.gz")
    assert evaluate(inst, None, *read_tour(GTSPLIB / "tours" / file, inst)).objective == float(length)


def test_reference_columns_say_who_found_each_tour():
    """Each row names its tour's finder: GLKH (the distributed tours, no date) or a run of this
    project (a best_known row with its ISO date); a certificate, where given, is a file."""
    for r in ROWS:
        if r["source"] == "GLKH":
            assert r["date"] == "", r["name"]
        else:
            assert r["source"].startswith("gtsp-bench ") and r["status"] == "best_known", r["name"]
            assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", r["date"]), r["name"]
        if r["certificate"]:
            assert (GTSPLIB / r["certificate"]).is_file(), r["name"]


@pytest.mark.parametrize("row", [_param(r) for r in ROWS])
def test_best_tour_prices_to_the_best_known_value(row):
    """The row's tour (GLKH's, or a shorter one kept since), read as (order, heads) and priced by
    the evaluator, has the row's length; AGTSP files give asymmetric instances, the others
    symmetric ones."""
    inst = read_instance(GTSPLIB / f"{row['name']}.gtsp.gz")
    assert (inst.n_clusters, inst.n_nodes) == (int(row["clusters"]), int(row["nodes"]))
    assert inst.symmetric == (row["type"] != "AGTSP")
    assert inst.edge_weight_type == row["edge_weight_type"]
    assert (inst.weights is None) == (row["edge_weight_type"] != "EXPLICIT")
    order, heads = read_tour(GTSPLIB / row["tour"], inst)
    assert evaluate(inst, None, order, heads).objective == float(row["best_known"])


def test_asymmetric_tours_are_priced_in_their_direction():
    """GLKH lists an AGTSP tour in the direction it travels: reversed, all but the smallest
    (4br17) cost more than the best-known value."""
    dearer = []
    for row in ASYMMETRIC:
        inst = gtsplib.read(row["name"])
        order, heads = gtsplib.best_tour(row["name"], inst)
        back = evaluate(inst, None, order[::-1], heads).objective
        assert back >= float(row["best_known"])
        dearer.append(back > float(row["best_known"]))
    assert sum(dearer) == len(ASYMMETRIC) - 1


def test_symmetric_only_solver_refuses_an_agtsp_file():
    """Through the CLI, a solver without asymmetric support refuses an AGTSP file: one line naming
    the file, exit code 2; one that has it solves the file."""
    path = GTSPLIB / "7ftv33.gtsp.gz"
    cli = [sys.executable, "-m", "gtsp_bench.cli", "solve", str(path), "--time-limit", "5"]
    out = subprocess.run([*cli, "--solver", "greedy+ls"], capture_output=True, text=True)
    assert out.returncode == 2 and out.stdout == ""
    assert out.stderr == (f"gtsp-bench: error: {path}: greedy+ls handles symmetric costs only "
                          "(this instance is asymmetric)\n")
    out = subprocess.run([*cli, "--solver", "greedy", "--json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert '"objective": ' in out.stdout


def test_reference_status():
    """Proven optima exactly for the symmetric instances up to 442 nodes and the larger ones with a
    shipped certificate; the five samples keep the status they always had."""
    refs = gtsplib.best_known()
    assert len(refs) == 143
    for ref in refs.values():
        certified = ref.nodes > 442 and bool(ref.certificate)
        assert ref.proven == ((ref.type == "GTSP" and ref.nodes <= 442) or certified), ref.name
    assert [refs[n].status for n in gtsplib.SAMPLES[:4]] == ["optimal"] * 4
    att = refs["107att532"]  # proven beyond 442 nodes only with a shipped certificate
    assert att.status == ("optimal" if att.certificate else "best_known")
    assert refs["11berlin52"].value == 4040 and refs["107att532"].value == 13464
    assert not refs["4br17"].symmetric and refs["4gr17"].symmetric
    assert sum(not r.symmetric for r in refs.values()) == 19


def test_a_reference_names_who_proved_it_and_whose_tour_it_is():
    """Rows measured against the library name the literature's proof up to 442 nodes, the shipped
    certificate beyond, and only the tour's source for a best known."""
    refs = gtsplib.best_known()
    assert refs["11berlin52"].reference_source == "Fischetti et al. 1997; GLKH tour"
    assert refs["99d493"].reference_source == "milp, certificate proofs/99d493.cert.json.gz; GLKH tour"
    open_file = next(r for r in refs.values() if not r.proven and r.source == "GLKH")  # files get proven
    assert open_file.reference_source == "GLKH"
    assert refs["464u2319"].reference_source == refs["464u2319"].source != "GLKH"  # a kept tour


def test_glns_table_agrees_with_best_known():
    """glns-45.csv's instances and sizes are those of best_known.csv, and its (published)
    best-known values are the published column; the best_known column is lower only where a
    shorter tour was kept since."""
    refs = gtsplib.best_known()
    with (GTSPLIB / "glns-45.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 45
    for r in rows:
        ref = refs[r["instance"]]
        assert (ref.nodes, ref.clusters) == (int(r["vertices"]), int(r["sets"]))
        assert ref.published == float(r["best_known"])
        assert ref.value == ref.published if ref.source == "GLKH" else ref.value < ref.published


def _library(tmp_path, status: str, value: int):
    """A copy of the library holding 11berlin52 only, its row given ``status`` and ``value``."""
    ref = replace(gtsplib.best_known()["11berlin52"], status=status, value=value, certificate="c.txt",
                  published=value)
    (tmp_path / "best_known.csv").write_text(gtsplib.format_best_known([ref]))
    (tmp_path / "11berlin52.gtsp.gz").write_bytes((GTSPLIB / "11berlin52.gtsp.gz").read_bytes())
    return tmp_path


def test_keep_tour_writes_a_shorter_tour_and_points_its_row_at_it(tmp_path):
    """A tour shorter than the row's best-known value: its file NAME.LENGTH.tour.gz prices to its
    length, the row names it with its value, source and date; status and certificate stay. A
    tour that is not shorter changes nothing."""
    where = _library(tmp_path, "best_known", 4100)
    order, heads = gtsplib.best_tour("11berlin52")
    row = gtsplib.keep_tour(where, "11berlin52", order, heads, "gtsp-bench lns 1s seed 3", "2026-11-27")
    assert row is not None and (row.value, row.tour) == (4040, "tours/11berlin52.4040.tour.gz")
    table = gtsplib.parse_best_known((where / "best_known.csv").read_text())
    assert table["11berlin52"] == row
    assert (row.status, row.source, row.date, row.certificate, row.published) == (
        "best_known", "gtsp-bench lns 1s seed 3", "2026-11-27", "c.txt", 4100)
    inst = read_instance(where / "11berlin52.gtsp.gz")
    assert evaluate(inst, None, *read_tour(where / row.tour, inst)).objective == 4040
    before = (where / "best_known.csv").read_text()
    assert gtsplib.keep_tour(where, "11berlin52", order, heads, "x", "2026-11-28") is None
    assert (where / "best_known.csv").read_text() == before


def test_keep_tour_refuses_a_tour_below_a_proven_optimum(tmp_path):
    """Below an ``optimal`` row the solver or the table is wrong: an error naming the table,
    nothing written."""
    where = _library(tmp_path, "optimal", 4100)
    order, heads = gtsplib.best_tour("11berlin52")
    with pytest.raises(InputError, match=r"best_known.csv: 11berlin52: .* below the proven optimum 4100"):
        gtsplib.keep_tour(where, "11berlin52", order, heads, "x", "2026-11-27")
    assert not (where / "tours").exists()


def test_keep_tour_fills_the_published_value_of_an_older_table(tmp_path):
    """A table without the published column gets the superseded value there."""
    where = _library(tmp_path, "best_known", 4100)
    ref = replace(gtsplib.parse_best_known((where / "best_known.csv").read_text())["11berlin52"],
                  published=None)
    (where / "best_known.csv").write_text(gtsplib.format_best_known([ref]))
    row = gtsplib.keep_tour(where, "11berlin52", *gtsplib.best_tour("11berlin52"), "x", "2026-11-27")
    assert row is not None and (row.value, row.published) == (4040, 4100)


@pytest.mark.parametrize(
    ("table", "tour", "message"),
    [
        ("name,clusters\nx,1\n", None, r"best_known.csv: missing column 'nodes'"),
        (None, ([0] * 11, [0] * 11), r"11berlin52.gtsp.gz: the tour to keep is not one: "),
    ],
)
def test_keep_tour_errors_name_the_file(tmp_path, table, tour, message):
    """A bad table or an infeasible tour is one InputError naming the file; nothing is written."""
    where = _library(tmp_path, "best_known", 4100)
    if table is not None:
        (where / "best_known.csv").write_text(table)
    order, heads = tour or gtsplib.best_tour("11berlin52")
    with pytest.raises(InputError, match=message):
        gtsplib.keep_tour(where, "11berlin52", order, heads, "x", "2026-11-27")
    assert not (where / "tours").exists()


def test_helpers_by_name():
    """names() in file order; path, tour_path, read and best_tour by name."""
    names = gtsplib.names()
    assert len(names) == 143 and names[0] == "3burma14" and set(gtsplib.SAMPLES) <= set(names)
    assert gtsplib.path("11berlin52") == GTSPLIB / "11berlin52.gtsp.gz"
    assert gtsplib.tour_path("11berlin52") == GTSPLIB / "tours" / "11berlin52.4040.tour.gz"
    inst = gtsplib.read("11berlin52")
    order, heads = gtsplib.best_tour("11berlin52")
    assert evaluate(inst, None, order, heads).objective == 4040
    assert gtsplib.best_tour("11berlin52", inst) == (order, heads)


def test_unknown_name_suggests_close_ones():
    """A misspelt name is an InputError that suggests the close names."""
    with pytest.raises(InputError, match=r"unknown GTSPLIB instance '11berlin5' \(did you mean 11berlin52"):
        gtsplib.path("11berlin5")


def test_missing_folder_is_a_clear_error(tmp_path, monkeypatch):
    """Pointed at a folder without the library (as from a wheel), every helper says where to get it."""
    monkeypatch.setenv(gtsplib.ENV_VAR, str(tmp_path))
    with pytest.raises(InputError, match=r"GTSPLIB not found .* not part of the installed package"):
        gtsplib.names()
    with pytest.raises(InputError, match="GTSPLIB not found"):
        gtsplib.read("11berlin52")


def test_the_folder_can_be_moved(tmp_path, monkeypatch):
    """GTSP_BENCH_GTSPLIB points at a copy of the library."""
    (tmp_path / "best_known.csv").write_text((GTSPLIB / "best_known.csv").read_text())
    (tmp_path / "11berlin52.gtsp.gz").write_bytes((GTSPLIB / "11berlin52.gtsp.gz").read_bytes())
    monkeypatch.setenv(gtsplib.ENV_VAR, str(tmp_path))
    assert gtsplib.folder() == tmp_path
    assert gtsplib.read("11berlin52").n_clusters == 11


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("name,clusters\nx,1\n", "missing column 'nodes'"),
        ("name,clusters,nodes,best_known,status,type,edge_weight_type,edge_weight_format,tour\n"
         "x,1,2,abc,optimal,GTSP,EUC_2D,,t\n", "line 2: bad row"),
        ("name,clusters,nodes,best_known,status,type,edge_weight_type,edge_weight_format,tour\n"
         "x,1,2,3,proven,GTSP,EUC_2D,,t\n", "status 'proven' is not one of optimal, best_known"),
        ("name,clusters,nodes,best_known,status,type,edge_weight_type,edge_weight_format,tour\n"
         "x,1,2,3,optimal,GTSP,EUC_2D,,t\nx,1,2,3,optimal,GTSP,EUC_2D,,t\n", "line 3: x is listed twice"),
        ("name,clusters,nodes,best_known,status,type,edge_weight_type,edge_weight_format,tour,published\n"
         "x,1,2,3,best_known,GTSP,EUC_2D,,t,2\n", "line 2: x's best_known 3 is above its published value 2"),
        ("name,clusters,nodes,best_known,status,type,edge_weight_type,edge_weight_format,tour,published\n"
         "x,1,2,3,best_known,GTSP,EUC_2D,,t,abc\n", "line 2: bad row"),
    ],
)
def test_bad_reference_tables(text, message):
    """A malformed best_known.csv is an InputError naming the line."""
    with pytest.raises(InputError, match=message):
        gtsplib.parse_best_known(text)


def test_reference_table_round_trips():
    """format_best_known writes what parse_best_known reads, the optional columns included."""
    table = gtsplib.best_known()
    text = gtsplib.format_best_known(table.values())
    assert gtsplib.parse_best_known(text) == table
    assert text == (gtsplib.folder() / "best_known.csv").read_text(encoding="utf-8")


def test_optional_reference_columns_default_to_empty():
    """A table without source, date, certificate and published columns reads them as empty."""
    text = ("name,clusters,nodes,best_known,status,type,edge_weight_type,edge_weight_format,tour\n"
            "x,1,2,3.5,optimal,GTSP,EUC_2D,,t\n")
    ref = gtsplib.parse_best_known(text)["x"]
    assert (ref.value, ref.source, ref.date, ref.certificate, ref.published) == (3.5, "", "", "", None)
    assert gtsplib.parse_best_known(gtsplib.format_best_known([ref]))["x"] == ref


_CERTIFIED = [r for r in gtsplib.best_known().values() if r.certificate]


def test_certificates_are_named_for_proven_rows_and_shipped():
    """Every named certificate is a shipped file of a proven row, every shipped file is named,
    and together they stay under 50 MB (a proof of about 1,400 leaves of 4,000 cuts, 201pr1002's,
    takes 13.9 MB; 212u1060's 13.4 MB)."""
    assert len(_CERTIFIED) >= 40
    for ref in _CERTIFIED:
        assert ref.proven and (GTSPLIB / ref.certificate).is_file(), ref.name
    shipped = {p.name for p in (GTSPLIB / "proofs").glob("*.cert.json.gz")}
    assert shipped == {ref.certificate.split("/")[-1] for ref in _CERTIFIED}
    assert sum((GTSPLIB / r.certificate).stat().st_size for r in _CERTIFIED) < 50_000_000


@pytest.mark.parametrize("ref", _CERTIFIED, ids=lambda r: r.name)
def test_shipped_certificates_prove_the_best_known_value(ref):
    """Each shipped certificate passes the checker and proves the table's value optimal."""
    from gtsp_bench.proof import check_certificate
    from gtsp_bench.proof.format import read_certificate

    result = check_certificate(gtsplib.read(ref.name), read_certificate(GTSPLIB / ref.certificate))
    assert result.proven and result.value == ref.value
