"""Instance sets and reference.csv: strict parsing, round trips, resolution, improvements."""

from __future__ import annotations

import os

import pytest

from gtsp_bench.data.io import write_instance
from gtsp_bench.data.sets import (
    REFERENCE_COLUMNS,
    Improvement,
    ReferenceRow,
    apply_improvements,
    format_reference,
    instance_stem,
    parse_reference,
    read_reference,
    read_set_file,
    resolve_set,
    update_reference,
    write_reference,
)
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance

HEADER = ",".join(REFERENCE_COLUMNS) + "\n"
ROWS = [
    ReferenceRow("uav-a", 0.5, 48123.25, 47990.5, "best_known", "lns 30s seed 0", "2026-11-23"),
    ReferenceRow("uav-a", 0.1, 0.1 + 0.2, None, "optimal", "milp 60s", "2026-01-02"),
    ReferenceRow("11berlin52", None, 4040.0, None, "optimal", "Fischetti et al. 1997", "1997-01-01"),
    ReferenceRow("big", None, 1234.5, 1200.0, "best_known", "GLKH, 2015", "2015-06-30"),
]


def test_reference_round_trip():
    """format_reference -> parse_reference gives the same rows back, floats exactly (repr), whole
    distance-only values as integers, the omega as a key, a comma in the source quoted."""
    text = format_reference(ROWS)
    assert text.splitlines()[0] == ",".join(REFERENCE_COLUMNS)
    assert "11berlin52,,4040,,optimal" in text
    assert "uav-a,0.1,0.30000000000000004,,optimal" in text
    assert '"GLKH, 2015"' in text
    back = parse_reference(text)
    assert list(back.values()) == ROWS
    assert back[("uav-a", 0.5)].label == "to best known"
    assert back[("11berlin52", None)].label == "to optimum"
    assert format_reference(back.values()) == text


@pytest.mark.parametrize("body, message", [
    ("", "line 1: header must be instance,omega,value,lower_bound,status,source,date"),
    ("instance,omega,value,status,source,date\n", "line 1: header must be"),
    ("a,0.5,10,,optimal,milp\n", "line 2: 6 fields, expected 7"),
    ("a,x,10,,optimal,milp,2026-01-01\n", "line 2: omega 'x' is not a number"),
    ("a,1.5,10,,optimal,milp,2026-01-01\n", "line 2: omega '1.5' is not in [0, 1]"),
    ("a,0.5,ten,,optimal,milp,2026-01-01\n", "line 2: value 'ten' is not a number"),
    ("a,0.5,inf,,optimal,milp,2026-01-01\n", "line 2: value 'inf' is not finite"),
    ("a,0.5,10,nan,optimal,milp,2026-01-01\n", "line 2: lower_bound 'nan' is not finite"),
    ("a,0.5,10,11,best_known,milp,2026-01-01\n", "line 2: lower_bound 11 is above the value 10"),
    ("a,0.5,10,,proven,milp,2026-01-01\n", "line 2: status 'proven' is not one of optimal, best_known"),
    ("a,0.5,10,,optimal,,2026-01-01\n", "line 2: empty source"),
    ("a,0.5,10,,optimal,milp,2026-13-01\n", "line 2: date '2026-13-01' is not an ISO date"),
    ("a,0.5,10,,optimal,milp,01/02/2026\n", "line 2: date '01/02/2026' is not an ISO date"),
    ("a,0.5,10,,optimal,milp,\n", "line 2: date '' is not an ISO date"),
    (",0.5,10,,optimal,milp,2026-01-01\n", "line 2: empty instance name"),
    ("a,0.5,10,,optimal,milp,2026-01-01\nb,,3,,optimal,x,2026-01-01\na,0.50,9,,optimal,y,2026-01-01\n",
     "line 4: a at omega 0.5 is listed twice"),
    ("a,,10,,optimal,milp,2026-01-01\n\na,,9,,optimal,y,2026-01-01\n", "line 4: a is listed twice"),
])
def test_bad_reference_text_names_the_line(body, message):
    """Every malformed row is one InputError naming its line and the problem."""
    text = body if message.startswith("line 1") else HEADER + body
    with pytest.raises(InputError) as e:
        parse_reference(text)
    assert str(e.value).startswith(message)
    assert "\n" not in str(e.value)


def test_read_reference_names_the_file(tmp_path):
    """A missing file is no references; a bad one is an error naming file and line."""
    path = tmp_path / "reference.csv"
    assert read_reference(path) == {}
    path.write_text(HEADER + "a,0.5,10,,optimal,milp,2026-01-01\na,0.5,10,,best,milp,2026-01-01\n")
    with pytest.raises(InputError, match=rf"^{path}: line 3: status 'best' is not one of"):
        read_reference(path)


def test_instance_stem():
    assert instance_stem("x/11berlin52.gtsp.gz") == "11berlin52"
    assert instance_stem("uav-K10-N20-s1-000.json") == "uav-K10-N20-s1-000"
    assert instance_stem("a.b.JSON.GZ") == "a.b"


def _uav_folder(tmp_path, name="myset", ks=(3, 3, 4)):
    folder = tmp_path / name
    for i, k in enumerate(ks):
        inst = generate_instance(k, 2, seed=i, name=f"{name}-{i:03d}")
        write_instance(inst, folder / f"{inst.name}.json")
    return folder


def test_resolve_committed_folder_and_file(tmp_path):
    """A committed name resolves under the instance folder, a path as given, a single file with
    its folder's reference.csv; files are in name order and stems are the instance names."""
    base = tmp_path / "instances"
    folder = _uav_folder(base, "uav-K3-N2-s1")
    (folder / "README.md").write_text("not an instance")
    write_reference(folder / "reference.csv", [ROWS[0]])
    s = resolve_set("uav-K3-N2-s1", base)
    assert s.name == "uav-K3-N2-s1" and s.reference_path == folder / "reference.csv"
    assert [f.stem for f in s.files] == ["uav-K3-N2-s1-000", "uav-K3-N2-s1-001", "uav-K3-N2-s1-002"]
    assert list(s.references.values()) == [ROWS[0]]
    assert resolve_set(str(folder), tmp_path / "elsewhere").files == s.files
    one = resolve_set(str(folder / "uav-K3-N2-s1-001.json"), base)
    assert [f.stem for f in one.files] == ["uav-K3-N2-s1-001"] and one.references == s.references
    inst, text, digest = read_set_file(s.files[0])
    assert inst.n_clusters == 3 and text.startswith("{") and len(digest) == 16


def test_resolve_errors(tmp_path):
    """Unknown names list the committed sets; empty folders and non-instance files are named."""
    base = tmp_path / "instances"
    _uav_folder(base, "uav-K3-N2-s1")
    (base / "empty").mkdir()
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(InputError, match=r"unknown set 'nope'.*committed sets: gtsplib, uav-K3-N2-s1;"):
        resolve_set("nope", base)
    with pytest.raises(InputError, match=r"empty: no instance files"):
        resolve_set("empty", base)
    with pytest.raises(InputError, match=r"notes.txt: not an instance file"):
        resolve_set(str(tmp_path / "notes.txt"), base)
    bad = base / "bad"
    bad.mkdir()
    (bad / "x.json").write_text("{")
    s = resolve_set("bad", base)
    with pytest.raises(InputError, match=r"x.json: "):
        read_set_file(s.files[0])


def test_gtsplib_set_reads_best_known_csv():
    """The gtsplib set is every instance of best_known.csv (the asymmetric ones too), whose values
    and statuses are its references (no reference.csv is kept beside it)."""
    from gtsp_bench.data import gtsplib

    s = resolve_set("gtsplib")
    table = gtsplib.best_known()
    assert [f.stem for f in s.files] == list(table) and len(s.files) == 143
    assert s.reference_path is None and not (gtsplib.folder() / "reference.csv").exists()
    ref = s.references[("11berlin52", None)]
    assert (ref.value, ref.status, ref.label) == (4040.0, "optimal", "to optimum")
    assert s.references[("3023d15112", None)].label == "to best known"  # no proof in sight
    assert s.references[("4br17", None)].value == 31  # AGTSP
    assert resolve_set(str(gtsplib.folder())).files == s.files


def test_apply_improvements_only_strictly_better_best_known():
    """Only a strictly better tour replaces a best_known value (the best one of several), with
    the solver, seed, limit and date as its source; equal values and optimal rows stay."""
    rows = {r.key: r for r in ROWS}
    found = [
        Improvement("s", "uav-a", 0.5, 48000.0, "lns", 1, 30.0),
        Improvement("s", "uav-a", 0.5, 47999.5, "aco", 0, 10.0),
        Improvement("s", "big", None, 1234.5, "lns", 0, 5.0),  # equal: no change
        Improvement("s", "11berlin52", None, 4040.0, "lns", 0, 5.0),  # equal to the optimum
    ]
    new, changes = apply_improvements(rows, found, "2026-11-24")
    assert new[0] == ReferenceRow("uav-a", 0.5, 47999.5, 47990.5, "best_known", "aco 10s seed 0",
                                  "2026-11-24")
    assert new[1:] == ROWS[1:]
    assert changes == ["uav-a omega 0.5: 48123.25 -> 47999.5 (aco 10s seed 0)"]
    with pytest.raises(InputError, match=r"11berlin52: lns found 4039.0, below the proven optimum 4040.0"):
        apply_improvements(rows, [Improvement("s", "11berlin52", None, 4039.0, "lns", 0, 5.0)], "x")


def test_update_reference_writes_atomically_and_only_on_change(tmp_path):
    """No improvement: the file is not rewritten; one: it is replaced whole, no temp file left."""
    path = tmp_path / "reference.csv"
    write_reference(path, ROWS)
    os.utime(path, (1, 1))
    assert update_reference(path, [Improvement("s", "big", None, 1300.0, "greedy", 0, 1.0)]) == []
    assert path.stat().st_mtime == 1
    changes = update_reference(path, [Improvement("s", "big", None, 1200.0, "lns", 2, 1.0)],
                               today="2026-11-24")
    assert changes == ["big: 1234.5 -> 1200.0 (lns 1s seed 2)"]
    after = read_reference(path)
    assert after[("big", None)] == ReferenceRow("big", None, 1200.0, 1200.0, "best_known", "lns 1s seed 2",
                                                "2026-11-24")
    assert [p.name for p in tmp_path.iterdir()] == ["reference.csv"]
    assert "big,,1200,1200,best_known" in path.read_text()
