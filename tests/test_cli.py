"""The gtsp-bench CLI: JSON shape, round trips, and every bad input exiting 2 with one line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from gtsp_bench.cli import main

from .conftest import GTSPLIB

KEYS = ["instance", "solver", "omega", "order", "heads", "objective", "energy", "distance",
        "status", "lower_bound", "runtime_s"]


@pytest.fixture
def k4(tmp_path: Path, capsys) -> Path:
    """A generated K = 4, N = 5 instance file."""
    path = tmp_path / "k4.json"
    assert main(["generate", "--clusters", "4", "--nodes", "5", "--seed", "1", "-o", str(path)]) == 0
    capsys.readouterr()
    return path


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_solve_json_shape(capsys, k4):
    """--json prints exactly one object with the documented keys and types."""
    code, out, _ = run(capsys, "solve", str(k4), "--solver", "brute", "--omega", "0.3", "--json")
    assert code == 0
    data = json.loads(out)
    assert list(data) == KEYS
    assert data["solver"] == "brute" and data["omega"] == 0.3 and data["status"] == "optimal"
    assert sorted(data["order"]) == [0, 1, 2, 3]
    assert len(data["heads"]) == 4 and all(0 <= h < 5 for h in data["heads"])
    assert set(data["energy"]) == {"total", "ground", "flight", "hover"}
    assert data["objective"] == data["energy"]["total"]
    assert data["lower_bound"] == pytest.approx(data["objective"])


def test_solve_then_evaluate_round_trip(capsys, k4, tmp_path):
    """A solution written by solve -o is re-priced identically by evaluate."""
    sol = tmp_path / "sol.json"
    code, out, _ = run(capsys, "solve", str(k4), "-s", "greedy", "-w", "0.6", "--json", "-o", str(sol))
    assert code == 0
    solved = json.loads(out)
    code, out, _ = run(capsys, "evaluate", str(k4), "--solution", str(sol), "-w", "0.6", "--json")
    assert code == 0
    evaluated = json.loads(out)
    assert list(evaluated) == KEYS
    assert evaluated["objective"] == solved["objective"]
    assert evaluated["energy"] == solved["energy"]


def test_gtsp_file_energy_is_null(capsys):
    """On a .gtsp file the objective is the tour length, energy and omega are null."""
    code, out, _ = run(capsys, "solve", str(GTSPLIB / "11berlin52.gtsp.gz"), "-s", "greedy", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["energy"] is None and data["omega"] is None
    assert data["objective"] == data["distance"] >= 4040


def test_summary_and_solvers_listing(capsys, k4):
    """Without --json a readable summary; 'solvers' lists one line per solver."""
    code, out, _ = run(capsys, "solve", str(k4), "-s", "greedy")
    assert code == 0 and "objective" in out and "depot ->" in out
    code, out, _ = run(capsys, "solvers")
    assert code == 0
    names = [line.split()[0] for line in out.splitlines()]
    assert "greedy" in names and "brute" in names


def _bad(tmp_path: Path, k4: Path) -> dict[str, tuple[list[str], str]]:
    malformed = tmp_path / "malformed.json"
    malformed.write_text("{not json")
    nan = tmp_path / "nan.json"
    nan.write_text('{"depot": [0, 0], "clusters": [[[0, NaN]]]}')
    empty = tmp_path / "empty.json"
    empty.write_text('{"depot": [0, 0], "clusters": [[[0, 1]], []]}')
    dup = tmp_path / "dup.gtsp"
    dup.write_text("NAME: d\nTYPE: GTSP\nDIMENSION: 2\nGTSP_SETS: 2\nEDGE_WEIGHT_TYPE: EUC_2D\n"
                   "NODE_COORD_SECTION\n1 0 0\n2 1 1\nGTSP_SET_SECTION\n1 1 2 -1\n2 2 -1\nEOF\n")
    empty_set = tmp_path / "empty-set.gtsp"
    empty_set.write_text(dup.read_text().replace("2 2 -1", "2 -1"))
    dim = tmp_path / "dim.gtsp"
    dim.write_text(dup.read_text().replace("DIMENSION: 2", "DIMENSION: 100000000000"))
    param = tmp_path / "param.json"
    param.write_text('{"depot": [0, 0], "clusters": [[[0, 1]]], "params": {"speed": 3}}')
    infeasible = tmp_path / "infeasible.json"
    infeasible.write_text('{"order": [0, 0, 1, 2], "heads": [0, 0, 0, 0]}')
    huge = tmp_path / "huge.json"
    huge.write_text('{"order": [0, 1, 2, 3%s], "heads": [0, 0, 0, 0]}' % ("0" * 30))
    bigint = tmp_path / "bigint.json"
    bigint.write_text('{"depot": [0, 0], "clusters": [[[0, 1%s]]]}' % ("0" * 400))
    missing = tmp_path / "missing.json"
    folder = tmp_path / "folder.json"
    folder.mkdir()
    return {
        "missing file": (["solve", str(missing), "-s", "greedy"], f"{missing}: no such file"),
        "malformed": (["solve", str(malformed), "-s", "greedy"], f"{malformed}: invalid JSON"),
        "nan": (["solve", str(nan), "-s", "greedy"], f"{nan}: invalid JSON: NaN is not a number"),
        "empty cluster": (["solve", str(empty), "-s", "greedy"], f"{empty}: clusters[1] is empty"),
        "empty .gtsp set": (["solve", str(empty_set), "-s", "greedy"], f"{empty_set}: set 2 is empty"),
        "duplicate": (["solve", str(dup), "-s", "greedy"], f"{dup}: node 2 is in set 1 and in set 2"),
        "huge dimension": (["solve", str(dim), "-s", "greedy"], f"{dim}: node 3 has no coordinates"),
        "omega": (["solve", str(k4), "-s", "greedy", "-w", "1.5"], "omega must be in [0, 1]"),
        "parameter": (["solve", str(param), "-s", "greedy"], "unknown energy parameter 'speed'"),
        "solver": (["solve", str(k4), "-s", "magic"], "unknown solver 'magic' (valid: "),
        "option": (["solve", str(k4), "-s", "brute", "-p", "ants=3"], "has no option 'ants'"),
        "time limit": (["solve", str(k4), "-s", "greedy", "-t", "-1"], "time limit must be > 0"),
        "infeasible": (["evaluate", str(k4), "--solution", str(infeasible)],
                       f"{infeasible}: infeasible solution: cluster 0 is visited 2 times"),
        "impossible generator": (["generate", "-k", "80", "-o", str(tmp_path / "g.json")],
                                 "would cover"),
        "not a number": (["solve", str(k4), "-s", "greedy", "-w", "abc"], "not a number: 'abc'"),
        "negative seed (solve)": (["solve", str(k4), "-s", "aco", "--seed", "-1"],
                                  "a seed must be an integer >= 0, got -1"),
        "negative seed (generate)": (["generate", "-k", "3", "--seed", "-2", "-o", str(missing)],
                                     "a seed must be an integer >= 0, got -2"),
        "negative seed (train)": (["train", "--seed", "-3", "-o", str(tmp_path / "p.pt")],
                                  "a seed must be an integer >= 0, got -3"),
        "brute too big": (["solve", str(k4), "-s", "brute", "-p", "max_tours=2"],
                          "brute force would enumerate"),
        "huge index": (["evaluate", str(k4), "--solution", str(huge)],
                       f"{huge}: infeasible solution: order holds an integer far outside"),
        "huge coordinate": (["solve", str(bigint), "-s", "greedy"],
                            f"{bigint}: clusters[0][0] has a NaN or infinite coordinate"),
        "output is a folder": (["solve", str(k4), "-s", "greedy", "-o", str(folder)],
                               f"{folder}: cannot write"),
        "generate onto a folder": (["generate", "-k", "3", "-o", str(folder)],
                                   f"{folder}: cannot write"),
    }


@pytest.mark.parametrize("case", [
    "missing file", "malformed", "nan", "empty cluster", "duplicate", "omega", "parameter",
    "solver", "option", "time limit", "infeasible", "impossible generator", "not a number",
    "brute too big", "output is a folder", "generate onto a folder", "huge index",
    "huge coordinate", "huge dimension", "negative seed (solve)", "negative seed (generate)",
    "negative seed (train)", "empty .gtsp set",
])
def test_bad_input_exits_2_with_one_line(capsys, tmp_path, k4, case):
    """Each bad input: exit code 2, one stderr line naming the problem, nothing on stdout."""
    argv, expected = _bad(tmp_path, k4)[case]
    try:
        code = main(argv)
    except SystemExit as e:  # argparse-level errors
        code = e.code
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1, err
    assert expected in err
    assert "Traceback" not in err


def test_failed_generate_writes_nothing(capsys, tmp_path):
    """An impossible generate leaves no file behind."""
    target = tmp_path / "g.json"
    assert main(["generate", "-k", "80", "-o", str(target)]) == 2
    assert not target.exists()


def test_console_script_starts_without_torch(tmp_path):
    """--help, solvers and solve with greedy never import torch (it costs seconds)."""
    inst = tmp_path / "k3.json"
    code = (
        "import sys\n"
        "from gtsp_bench.cli import main\n"
        f"main(['generate', '-k', '3', '-n', '4', '-o', {str(inst)!r}])\n"
        "main(['solvers'])\n"
        f"main(['solve', {str(inst)!r}, '-s', 'greedy', '--json'])\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "assert 'torch' not in sys.modules, 'torch was imported'\n"
        "assert 'highspy' not in sys.modules and 'ortools' not in sys.modules\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr


def test_console_script_is_installed():
    """The gtsp-bench entry point runs from the virtual environment."""
    exe = Path(sys.executable).with_name("gtsp-bench")
    proc = subprocess.run([str(exe), "--help"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0
    assert "generalized TSP" in proc.stdout
