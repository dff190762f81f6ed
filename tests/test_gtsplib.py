"""The bundled GTSPLIB (instances/gtsplib/): GLKH's best tours priced by the one evaluator, the
reference table, and the by-name helpers of gtsp_bench.gtsplib.

Every symmetric instance of the library (124 of 143, up to 85,900 nodes) is read and GLKH's best
tour of it priced with :func:`gtsp_bench.energy.evaluate`; the length must equal the published
best-known value exactly. This checks the reader (every header variant, edge-weight type and
explicit format that occurs) and every distance rule against an independent implementation. The
whole library takes about 3 s, so it runs in the default ``make test``; no marker is needed. The
19 asymmetric (AGTSP) instances are checked to be refused with the one clean input error.
"""

from __future__ import annotations

import csv

import pytest

from gtsp_bench import gtsplib
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.io import read_instance, read_tour

from .conftest import GTSPLIB

with (GTSPLIB / "best_known.csv").open() as _f:
    ROWS = list(csv.DictReader(_f))
SYMMETRIC = [r for r in ROWS if r["type"] != "AGTSP"]
ASYMMETRIC = [r for r in ROWS if r["type"] == "AGTSP"]


def test_the_library_is_complete():
    """143 instances, each with its file and GLKH's tour; nothing else in the folder."""
    assert len(ROWS) == 143 and len(ASYMMETRIC) == 19
    files = {p.name for p in GTSPLIB.glob("*.gtsp.gz")}
    assert files == {f"{r['name']}.gtsp.gz" for r in ROWS}
    tours = {f"tours/{p.name}" for p in (GTSPLIB / "tours").iterdir()}
    assert tours == {r["tour"] for r in ROWS}
    for r in ROWS:  # the tour file's name carries its length: NAME.LENGTH.tour.gz
        assert r["tour"] == f"tours/{r['name']}.{r['best_known']}.tour.gz"


@pytest.mark.parametrize("row", SYMMETRIC, ids=lambda r: r["name"])
def test_best_tour_prices_to_the_best_known_value(row):
    """GLKH's tour, read as (order, heads) and priced by the evaluator, has the published length."""
    inst = read_instance(GTSPLIB / f"{row['name']}.gtsp.gz")
    assert (inst.n_clusters, inst.n_nodes) == (int(row["clusters"]), int(row["nodes"]))
    order, heads = read_tour(GTSPLIB / row["tour"], inst)
    assert evaluate(inst, None, order, heads).objective == float(row["best_known"])


@pytest.mark.parametrize("row", ASYMMETRIC, ids=lambda r: r["name"])
def test_asymmetric_instances_are_refused_cleanly(row):
    """AGTSP files (whatever their TYPE line looks like) are one InputError naming the file."""
    path = GTSPLIB / f"{row['name']}.gtsp.gz"
    with pytest.raises(InputError, match=rf"^{path}: asymmetric GTSP \(AGTSP\) is not supported$"):
        read_instance(path)


def test_reference_status():
    """Proven optima exactly for the symmetric instances up to 442 nodes; the five samples keep
    the status they always had."""
    refs = gtsplib.best_known()
    assert len(refs) == 143
    for ref in refs.values():
        assert ref.proven == (ref.type == "GTSP" and ref.nodes <= 442), ref.name
    assert [refs[n].status for n in gtsplib.SAMPLES] == ["optimal"] * 4 + ["best_known"]
    assert refs["11berlin52"].value == 4040 and refs["107att532"].value == 13464
    assert not refs["4br17"].symmetric and refs["4gr17"].symmetric


def test_glns_table_agrees_with_best_known():
    """glns-45.csv's instances, sizes and best-known values are those of best_known.csv."""
    refs = gtsplib.best_known()
    with (GTSPLIB / "glns-45.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 45
    for r in rows:
        ref = refs[r["instance"]]
        assert (ref.nodes, ref.clusters, ref.value) == (
            int(r["vertices"]), int(r["sets"]), float(r["best_known"]))


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
    ],
)
def test_bad_reference_tables(text, message):
    """A malformed best_known.csv is an InputError naming the line."""
    with pytest.raises(InputError, match=message):
        gtsplib.parse_best_known(text)
