"""The gtsp-bench CLI: JSON shape, round trips, and every bad input exiting 2 with one line."""

from __future__ import annotations

import gzip
import json
import os
import subprocess
import sys
from pathlib import Path

import matplotlib.image as mpimg
import pytest

from gtsp_bench.cli import main
from tests.conftest import GTSPLIB, REPO

KEYS = ["instance", "solver", "omega", "order", "heads", "objective", "energy", "distance",
        "status", "lower_bound", "runtime_s", "trajectory", "stats"]


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
    assert isinstance(data["stats"], dict)


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
    berlin_tour = GTSPLIB / "tours" / "11berlin52.4040.tour.gz"
    kroa = GTSPLIB / "20kroA100.gtsp.gz"
    feasible = tmp_path / "feasible.json"
    feasible.write_text('{"order": [3, 2, 1, 0], "heads": [0, 1, 2, 3]}')
    bad_bound = tmp_path / "bad-bound.json"
    bad_bound.write_text('{"order": [3, 2, 1, 0], "heads": [0, 1, 2, 3], "lower_bound": "low"}')
    high_bound = tmp_path / "high-bound.json"
    high_bound.write_text('{"order": [3, 2, 1, 0], "heads": [0, 1, 2, 3], "lower_bound": 1e12}')
    warm = ["solve", str(k4), "-s", "lns", "-t", "1", "--initial"]
    return {
        "initial infeasible": ([*warm, str(infeasible)],
                               f"{infeasible}: infeasible solution: cluster 0 is visited 2 times"),
        "initial missing": ([*warm, str(missing)], f"{missing}: no such file"),
        "initial bound not a number": ([*warm, str(bad_bound)],
                                       f"{bad_bound}: 'lower_bound' must be a number or null"),
        "initial bound above": ([*warm, str(high_bound)], f"{high_bound}: the initial solution's "
                                "lower bound 1000000000000.0 is above its objective"),
        "initial for aco": (["solve", str(k4), "-s", "aco", "--initial", str(feasible)],
                            f"{feasible}: solver 'aco' cannot start from an initial solution"),
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
        "tour of another instance": (["evaluate", str(kroa), "--solution", str(berlin_tour)],
                                     f"{berlin_tour}: the tour lists 11 nodes, but a tour of 20kroA100"),
        "tour not .tour": (["solve", str(k4), "-s", "greedy", "--tour", str(tmp_path / "t.txt")],
                           "t.txt: a tour file's name ends in .tour (or .tour.gz)"),
        "plot not .png": (["plot", str(k4), "-o", str(tmp_path / "k4.pdf")],
                          "k4.pdf: plot writes PNG; name the output FILE.png"),
        "plot infeasible": (["plot", str(k4), "--solution", str(infeasible), "-o", str(tmp_path / "p.png")],
                            f"{infeasible}: infeasible solution: cluster 0 is visited 2 times"),
    }


@pytest.mark.parametrize("case", [
    "missing file", "malformed", "nan", "empty cluster", "duplicate", "omega", "parameter",
    "solver", "option", "time limit", "infeasible", "impossible generator", "not a number",
    "brute too big", "output is a folder", "generate onto a folder", "huge index",
    "huge coordinate", "huge dimension", "negative seed (solve)", "negative seed (generate)",
    "negative seed (train)", "empty .gtsp set", "tour of another instance", "tour not .tour",
    "plot not .png", "plot infeasible", "initial infeasible", "initial missing",
    "initial bound not a number", "initial bound above", "initial for aco",
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


def test_solve_tour_then_evaluate_and_plot_it(capsys, k4, tmp_path):
    """solve --tour writes a tour file that evaluate re-prices at the solver's objective, and plot
    draws it beside a JSON solution: a whole PNG, two panels wide, written atomically."""
    sol, tour, png = tmp_path / "sol.json", tmp_path / "dp.tour", tmp_path / "k4.png"
    code, out, _ = run(capsys, "solve", str(k4), "-s", "dp", "-w", "0.3", "--json", "--tour", str(tour))
    assert code == 0
    solved = json.loads(out)
    assert "TYPE : TOUR" in tour.read_text() and "at omega = 0.3" in tour.read_text()
    code, out, _ = run(capsys, "evaluate", str(k4), "--solution", str(tour), "-w", "0.3", "--json")
    assert code == 0
    evaluated = json.loads(out)
    assert (evaluated["order"], evaluated["heads"]) == (solved["order"], solved["heads"])
    assert evaluated["objective"] == solved["objective"]
    assert run(capsys, "solve", str(k4), "-s", "greedy", "-w", "0.3", "-o", str(sol))[0] == 0
    code, out, err = run(capsys, "plot", str(k4), "--solution", str(sol), "--solution", str(tour),
                         "-w", "0.3", "-o", str(png))
    assert code == 0 and out == "" and err == f"wrote {png} (2 solutions)\n"
    assert png.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    height, width, _ = mpimg.imread(png).shape
    assert 400 <= height <= 700 and 2 * height - 100 <= width <= 2 * height + 100
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dp.tour", "k4.json", "k4.png", "sol.json"]


def test_solve_tour_of_a_gtsplib_file(capsys, tmp_path):
    """On a GTSPLIB file --tour writes the file's node ids (gzip-compressed for .tour.gz) with
    GLKH's 'Length = ' comment, and evaluate re-prices the tour at the solver's length."""
    berlin, tour = str(GTSPLIB / "11berlin52.gtsp.gz"), tmp_path / "b.tour.gz"
    code, out, _ = run(capsys, "solve", berlin, "-s", "greedy", "--json", "--tour", str(tour))
    assert code == 0
    solved = json.loads(out)
    assert f"COMMENT : Length = {solved['objective']:g}" in gzip.decompress(tour.read_bytes()).decode()
    code, out, _ = run(capsys, "evaluate", berlin, "--solution", str(tour), "--json")
    assert code == 0 and json.loads(out)["objective"] == solved["objective"]


def test_plot_a_gtsplib_file_with_coordinates(capsys, tmp_path):
    """A GTSPLIB file with its GLKH tour (no base station): one panel, a PNG of a sensible size."""
    png = tmp_path / "berlin.png"
    code, out, _ = run(capsys, "plot", str(GTSPLIB / "11berlin52.gtsp.gz"), "--solution",
                       str(GTSPLIB / "tours" / "11berlin52.4040.tour.gz"), "-o", str(png))
    assert code == 0 and out == ""
    height, width, _ = mpimg.imread(png).shape
    assert 400 <= height <= 700 and 400 <= width <= 700


def test_plot_refuses_a_file_of_weights_alone(capsys, tmp_path):
    """A GTSPLIB file without coordinates: exit 2, one stderr line naming it, no file written."""
    path, png = GTSPLIB / "10gr48.gtsp.gz", tmp_path / "gr.png"
    code, out, err = run(capsys, "plot", str(path), "-o", str(png))
    assert code == 2 and out == ""
    assert err == (f"gtsp-bench: error: {path}: no node coordinates to draw: the file gives EXPLICIT "
                   "weights without a DISPLAY_DATA_SECTION\n")
    assert list(tmp_path.iterdir()) == []
def test_solve_json_trajectory_and_progress(capsys, k4):
    """--json carries the trajectory (objectives never rise, the last is the answer); with
    --progress each of its points is one stderr line and stdout stays the JSON alone."""
    code, out, err = run(capsys, "solve", str(k4), "-s", "milp", "--json", "--progress")
    assert code == 0
    data = json.loads(out)
    points = data["trajectory"]
    assert points and all(list(p) == ["time_s", "objective", "lower_bound"] for p in points)
    objectives = [p["objective"] for p in points]
    assert objectives == sorted(objectives, reverse=True) and objectives[-1] == data["objective"]
    assert points[-1]["lower_bound"] == data["lower_bound"]
    lines = err.strip().splitlines()
    assert len(lines) == len(points) and all(line.startswith("gtsp-bench: progress: ") for line in lines)
    assert f"objective {data['objective']:.6f}" in lines[-1] and lines[-1].endswith(" %")


def test_solve_from_an_initial_solution(capsys, k4, tmp_path):
    """--initial SOL.json warm-starts lns from a file 'solve --json' wrote: the answer is no
    worse; from an optimal milp answer (its lower bound meets its objective) lns returns that
    tour at once."""
    greedy, optimal = tmp_path / "greedy.json", tmp_path / "optimal.json"
    assert run(capsys, "solve", str(k4), "-s", "greedy", "-o", str(greedy))[0] == 0
    assert run(capsys, "solve", str(k4), "-s", "milp", "-o", str(optimal))[0] == 0
    code, out, _ = run(capsys, "solve", str(k4), "-s", "lns", "-t", "0.5", "--initial", str(greedy),
                       "--json")
    assert code == 0
    assert json.loads(out)["objective"] <= json.loads(greedy.read_text())["objective"]
    code, out, _ = run(capsys, "solve", str(k4), "-s", "lns", "-t", "30", "--initial", str(optimal),
                       "--json")
    assert code == 0
    data, best = json.loads(out), json.loads(optimal.read_text())
    assert (data["order"], data["heads"], data["objective"]) == (best["order"], best["heads"],
                                                                 best["objective"])
    assert data["runtime_s"] < 1.0


def test_a_solver_refusing_the_instance_names_the_file(capsys, tmp_path):
    """dp refusing a K = 25 instance (its table would not fit its memory limit): one line that
    starts with the file, exit code 2, nothing on stdout."""
    path = tmp_path / "k25.json"
    assert run(capsys, "generate", "--clusters", "25", "--seed", "1", "-o", str(path))[0] == 0
    code, out, err = run(capsys, "solve", str(path), "--solver", "dp", "--json")
    assert code == 2 and out == ""
    assert err.startswith(f"gtsp-bench: error: {path}: dp needs ") and err.count("\n") == 1


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
        f"assert main(['generate', '-k', '3', '-n', '4', '-o', {str(inst)!r}]) == 0\n"
        "assert main(['solvers']) == 0\n"
        f"assert main(['solve', {str(inst)!r}, '-s', 'greedy', '--json']) == 0\n"
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


def _cli_subprocess(argv: list[str], *, setup: str = "", limit_bytes: int | None = None,
                    cwd: Path | None = None) -> subprocess.CompletedProcess:
    """Run ``main(argv)`` in a fresh interpreter (after ``setup``), optionally under ``ulimit -v``."""
    code = f"import sys\n{setup}\nfrom gtsp_bench.cli import main\nsys.exit(main({argv!r}))\n"

    def cap() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))

    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          cwd=cwd or REPO, env=env, preexec_fn=cap if limit_bytes else None)


def test_solve_json_stays_one_object_when_a_library_prints_on_fd_1(k4):
    """A solver writing a banner straight to file descriptor 1 and print()ing (as highspy 1.16
    does): stdout is still exactly one JSON object; the noise goes to stderr."""
    setup = "from tests.runner_solvers import register\nregister()"
    proc = _cli_subprocess(["solve", str(k4), "-s", "t-banner", "--json"], setup=setup)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    assert list(result) == KEYS and result["solver"] == "t-banner"
    assert "banner on fd 1" in proc.stderr and "a stray print" in proc.stderr
    proc = _cli_subprocess(["solve", str(k4), "-s", "t-banner"], setup=setup)
    assert proc.returncode == 0 and proc.stdout.startswith("instance   ")
    assert "fd 1" not in proc.stdout and "stray" not in proc.stdout


def test_stdout_is_restored_after_each_command(tmp_path, capfd):
    """main() in-process (fd-level capture): the answer reaches stdout, fd 1 is stdout again."""
    k3 = tmp_path / "k3.json"
    assert main(["generate", "-k", "3", "-o", str(k3)]) == 0
    assert capfd.readouterr().out == ""
    assert main(["solve", str(k3), "-s", "greedy", "--json"]) == 0
    out, _ = capfd.readouterr()
    assert json.loads(out)["solver"] == "greedy"
    os.write(1, b"after\n")
    assert capfd.readouterr().out == "after\n"


def _far_point_instance(tmp_path: Path) -> Path:
    path = tmp_path / "far.json"
    path.write_text(json.dumps({"depot": [0, 0], "clusters": [[[0, 0], [1e300, 1e300]], [[5, 5]],
                                                            [[9, 1]]]}))
    return path


def test_every_solver_refuses_a_point_at_1e300_naming_the_file(capsys, tmp_path):
    """A point at (1e300, 1e300) is finite but no distance or energy of it is: every registered
    solver exits 2 with one line naming the file and the value."""
    from gtsp_bench.registry import solver_names

    path = _far_point_instance(tmp_path)
    for name in solver_names():
        code = main(["solve", str(path), "-s", name, "--json"])
        out, err = capsys.readouterr()
        assert code == 2 and out == "", (name, err)
        assert err.count("\n") == 1 and err.startswith(f"gtsp-bench: error: {path}: clusters[0][1]")
        assert "1e+300" in err


def test_generate_refuses_a_size_it_cannot_hold_at_once(capsys, tmp_path, monkeypatch):
    """-n 100000000 with 8 GiB available: one line before any allocation, naming a size that
    fits, and no file."""
    from gtsp_bench import checks

    monkeypatch.setattr(checks, "memory_limit_bytes", lambda: 8 * 2**30)
    target = tmp_path / "big.json"
    code = main(["generate", "-k", "4", "-n", "100000000", "-o", str(target)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "needs about 119 GiB of memory, more than the 8 GiB available" in err
    assert "use at most about 6710886 nodes per cluster (--nodes)" in err
    assert not target.exists()


def test_generate_refuses_under_a_memory_cap(tmp_path):
    """The same under `ulimit -v` (2 GiB), whatever the machine has."""
    proc = _cli_subprocess(["generate", "-k", "4", "-n", "100000000", "-o", str(tmp_path / "b.json")],
                           limit_bytes=2 * 2**30)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert "GiB of memory, more than the" in proc.stderr


def test_dp_above_the_machine_memory_is_one_line(tmp_path, capsys):
    """dp -p max_memory_gb=500 on K = 25 under a 3 GiB cap: its 187 GiB table cannot be made;
    exit 2 with one line naming what ran out and what to try instead."""
    k25 = tmp_path / "k25.json"
    assert main(["generate", "-k", "25", "-o", str(k25)]) == 0
    capsys.readouterr()
    proc = _cli_subprocess(["solve", str(k25), "-s", "dp", "-p", "max_memory_gb=500"],
                           limit_bytes=3 * 2**30)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert proc.stderr.startswith("gtsp-bench: error: out of memory (dp's 188 GiB table for")
    assert "max_memory_gb below 188" in proc.stderr


def test_memory_errors_are_one_line_per_command():
    """Each command's out-of-memory line names the allocation and a smaller setting."""
    from gtsp_bench.cli import _memory_message

    msg = _memory_message("train", MemoryError("Unable to allocate 3 GiB\nmore"))
    assert msg == "out of memory (Unable to allocate 3 GiB); use a smaller --batch or --val-size"
    assert _memory_message("bench", MemoryError()).startswith("out of memory (an allocation failed)")


@pytest.mark.parametrize("argv", [["--nope"], ["generate", "--clusters", "x", "-o", "a.json"],
                                  ["solve"], ["bench", "--bogus"]])
def test_bad_arguments_read_gtsp_bench_error_in_every_command(capsys, argv):
    """argparse's complaints, of the main parser and of every sub-command, are the one line
    'gtsp-bench: error: ...' (never 'gtsp-bench solve: error:'), exit code 2."""
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2
    assert err.startswith("gtsp-bench: error: ") and err.count("\n") == 1
