"""Packaging: the wheel holds what an installation needs, an installed copy runs every solver, the
example plug-in registers by entry point, and the project's imports have no cycle.

The wheel tests (marker ``packaging``) build with ``pip wheel --no-deps`` from a copy of the
sources in a temporary folder, without build isolation when this interpreter's setuptools can
build a wheel itself (setuptools >= 70.1, or the ``wheel`` package), else with pip's isolated
build, which fetches setuptools from the configured package index. They take about 30 s in all
and run in ``make test``; ``pytest -m "not packaging"`` leaves them out.
"""

from __future__ import annotations

import ast
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest
from gtsp_bench.solvers import BUILTIN

from gtsp_bench.data.io import read_instance
from gtsp_bench.energy import evaluate

from .conftest import GTSPLIB, REPO

#: What the wheel is built from (copied, so that the build leaves nothing in the checkout).
SOURCES = ("pyproject.toml", "README.md", "gtsp_bench", "solvers")
_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info", "*.state.pt")
EXAMPLE = REPO / "examples" / "gtsp-bench-nearest"


# ---------------------------------------------------------------------- helpers
def _builds_without_isolation() -> bool:
    """Whether this interpreter's setuptools can build a wheel with no download."""
    try:
        import setuptools
    except ImportError:
        return False
    if importlib.util.find_spec("wheel") is not None:
        return True
    major, minor = (int(p) for p in setuptools.__version__.split(".")[:2])
    return (major, minor) >= (70, 1)


def _run(argv: list[str], *, cwd: Path, pythonpath: Path | None = None,
         extra: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env |= {"PIP_DISABLE_PIP_VERSION_CHECK": "1", "PIP_NO_INPUT": "1"} | (extra or {})
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def _pip(*args: str, cwd: Path) -> None:
    isolation = ["--no-build-isolation"] if _builds_without_isolation() else []
    done = _run([sys.executable, "-m", "pip", *args, *isolation, "-q"], cwd=cwd)
    assert done.returncode == 0, f"pip {' '.join(args)} failed:\n{done.stdout}\n{done.stderr}"


def _cli(*args: str, cwd: Path, pythonpath: Path | None = None) -> subprocess.CompletedProcess:
    return _run([sys.executable, "-m", "gtsp_bench.cli", *args], cwd=cwd, pythonpath=pythonpath)


def _optional_packages() -> set[str]:
    """Packages of the optional extras other than ``dev`` (gurobipy, pyvrp, ...), from pyproject."""
    extras = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    names = set()
    for extra, reqs in extras.items():
        if extra != "dev":
            for req in reqs:
                names.add(req.split(">")[0].split("=")[0].split("<")[0].split("[")[0].strip())
    return names


# ---------------------------------------------------------------------- the wheel
@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """A wheel built from a copy of the sources."""
    src = tmp_path_factory.mktemp("src")
    for name in SOURCES:
        path = REPO / name
        if path.is_dir():
            shutil.copytree(path, src / name, ignore=_IGNORE)
        else:
            shutil.copy2(path, src / name)
    out = tmp_path_factory.mktemp("wheel")
    _pip("wheel", "--no-deps", "-w", str(out), str(src), cwd=out)
    (built,) = out.glob("gtsp_bench-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> Path:
    """The wheel installed into a bare target folder."""
    target = tmp_path_factory.mktemp("target")
    _pip("install", "--no-deps", "--target", str(target), str(wheel), cwd=target)
    return target


@pytest.mark.packaging
def test_wheel_holds_the_package_and_the_checkpoints(wheel):
    """One import root (gtsp_bench, no top-level solvers), every module of both folders, the
    learned checkpoints as package data, the console script; not the GTSPLIB instances."""
    names = set(zipfile.ZipFile(wheel).namelist())
    tops = {n.split("/")[0] for n in names}
    assert tops == {"gtsp_bench", wheel.name.split("-py3")[0] + ".dist-info"}, tops
    expected = {f"gtsp_bench/{p.relative_to(REPO / 'gtsp_bench').as_posix()}"
                for p in (REPO / "gtsp_bench").rglob("*.py")}
    expected |= {f"gtsp_bench/solvers/{p.relative_to(REPO / 'solvers').as_posix()}"
                 for p in (REPO / "solvers").rglob("*.py")}
    assert expected <= names, sorted(expected - names)
    checkpoints = sorted(p.name for p in (REPO / "solvers" / "learned" / "checkpoints").glob("*.pt")
                         if not p.name.endswith(".state.pt"))
    assert checkpoints, "no checkpoints in the repository"
    for name in checkpoints:
        assert f"gtsp_bench/solvers/learned/checkpoints/{name}" in names
    assert not any(n.endswith(".gtsp.gz") or n.startswith("instances/") for n in names)
    dist_info = next(n for n in names if n.endswith(".dist-info/entry_points.txt"))
    assert "gtsp-bench = gtsp_bench.cli:main" in zipfile.ZipFile(wheel).read(dist_info).decode()


# Run once in the installed copy: each solver through the CLI module exactly as `python -m
# gtsp_bench.cli solve ...` runs it (runpy), in one process so that torch is imported once.
_DRIVER = """
import contextlib, io, json, runpy, sys
instance, names = sys.argv[1], sys.argv[2:]
results = {}
for name in names:
    out, err = io.StringIO(), io.StringIO()
    sys.argv = ["gtsp-bench", "solve", instance, "--solver", name, "--time-limit", "2", "--json"]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            runpy.run_module("gtsp_bench.cli", run_name="__main__", alter_sys=True)
            code = 0
        except SystemExit as e:
            code = e.code
    results[name] = [code, out.getvalue(), err.getvalue()]
mine = [m for m in list(sys.modules) if m == "gtsp_bench" or m.startswith("gtsp_bench.")]
modules = {m: getattr(sys.modules[m], "__file__", None) for m in mine}
checkpoints = sorted({str(sys.modules[m].CHECKPOINT_DIR) for m in mine
                      if hasattr(sys.modules[m], "CHECKPOINT_DIR")})
print(json.dumps({"results": results, "modules": modules, "checkpoints": checkpoints}))
"""


@pytest.fixture(scope="module")
def installed_run(installed, tmp_path_factory) -> dict:
    """Every built-in solver solved through the installed copy's CLI, from another folder.

    The numba kernels run as plain Python here (``NUMBA_DISABLE_JIT=1``): compiling them afresh
    for the installed copy took about 140 s of the suite, and the same sources are compiled and
    run from the checkout by the solvers' own tests. What this run checks is which files an
    installation imports and that each solver's answer is the evaluator's."""
    work = tmp_path_factory.mktemp("work")
    done = _cli("generate", "--clusters", "3", "--seed", "1", "-o", "k3.json", cwd=work,
                pythonpath=installed)
    assert done.returncode == 0, done.stderr
    listing = _cli("solvers", cwd=work, pythonpath=installed)
    assert listing.returncode == 0, listing.stderr
    names = [b.name for b in BUILTIN]
    done = _run([sys.executable, "-c", _DRIVER, "k3.json", *names], cwd=work, pythonpath=installed,
                extra={"NUMBA_DISABLE_JIT": "1"})
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout.strip().splitlines()[-1])
    data["listed"] = [line.split()[0] for line in listing.stdout.splitlines()]
    data["instance"] = work / "k3.json"
    return data


@pytest.mark.packaging
def test_installed_copy_is_the_one_used(installed, installed_run):
    """From another folder, with the target on PYTHONPATH, every gtsp_bench module (solvers and
    the learned checkpoints included) comes from the installed copy, and every solver is listed."""
    modules = installed_run["modules"]
    assert "gtsp_bench.solvers.learned.drl" in modules
    for name, file in modules.items():
        assert file is None or Path(file).is_relative_to(installed), (name, file)
    assert installed_run["checkpoints"], "no module of the learned solvers has CHECKPOINT_DIR"
    for folder in installed_run["checkpoints"]:
        assert Path(folder).is_relative_to(installed) and any(Path(folder).glob("*.pt")), folder
    assert {b.name for b in BUILTIN} <= set(installed_run["listed"])


@pytest.mark.packaging
@pytest.mark.parametrize("name", [b.name for b in BUILTIN])
def test_installed_copy_runs_every_solver(installed_run, name):
    """Each registered solver solves a generated instance through the installed CLI, and the
    objective is the evaluator's. A solver whose optional extra is not usable here (not installed,
    or no licence) is skipped with its own error message."""
    code, out, err = installed_run["results"][name]
    if code == 2 and (any(p in err for p in _optional_packages()) or "licen" in err):
        pytest.skip(f"optional extra not usable here: {err.strip()}")
    assert code == 0, err
    result = json.loads(out)
    inst = read_instance(installed_run["instance"])
    assert result["objective"] == evaluate(inst, 0.5, result["order"], result["heads"]).objective


# ---------------------------------------------------------------------- the example plug-in
@pytest.mark.packaging
def test_example_plugin_registers_by_entry_point(tmp_path):
    """examples/gtsp-bench-nearest installed into a target folder: with it on PYTHONPATH the CLI
    lists 'nearest' (described by its docstring) and solves with it; a plug-in that takes a
    built-in's name is skipped with a warning, and one that cannot be imported is left out with a
    warning while every other solver stays."""
    src = tmp_path / "src"
    shutil.copytree(EXAMPLE, src, ignore=_IGNORE)
    target = tmp_path / "target"
    _pip("install", "--no-deps", "--target", str(target), str(src), cwd=tmp_path)
    # A second, hand-made distribution: a clash with a built-in and a broken plug-in.
    meta = target / "bad_plugins-0.1.dist-info"
    meta.mkdir()
    (meta / "METADATA").write_text("Metadata-Version: 2.1\nName: bad-plugins\nVersion: 0.1\n")
    (meta / "entry_points.txt").write_text(
        "[gtsp_bench.solvers]\ngreedy = gtsp_bench_nearest:NearestCenter\n"
        "broken = no_such_module_anywhere:Solver\n")

    listing = _cli("solvers", cwd=tmp_path, pythonpath=target)
    assert listing.returncode == 0, listing.stderr
    lines = {line.split()[0]: line for line in listing.stdout.splitlines()}
    assert lines["nearest"].split(None, 1)[1] == (
        "Each cluster's most central node; clusters visited by angle around the depot. "
        "(plug-in from gtsp-bench-nearest)")
    assert "paper's greedy" in lines["greedy"] and "broken" not in lines
    assert {b.name for b in BUILTIN} <= set(lines)
    assert ("warning: solver 'greedy' from entry point 'gtsp_bench_nearest:NearestCenter' is "
            "already registered; skipped") in listing.stderr
    assert "warning: solver 'broken' is not available" in listing.stderr

    generated = _cli("generate", "--clusters", "5", "--seed", "2", "-o", "k5.json", cwd=tmp_path)
    assert generated.returncode == 0, generated.stderr
    for path in (tmp_path / "k5.json", GTSPLIB / "11berlin52.gtsp.gz"):
        done = _cli("solve", str(path), "--solver", "nearest", "--json", cwd=tmp_path, pythonpath=target)
        assert done.returncode == 0, done.stderr
        result = json.loads(done.stdout)
        assert result["solver"] == "nearest"
        inst = read_instance(path)
        omega = 0.5 if inst.is_uav else None
        assert result["objective"] == evaluate(inst, omega, result["order"], result["heads"]).objective
    broken = _cli("solve", str(tmp_path / "k5.json"), "--solver", "broken", cwd=tmp_path, pythonpath=target)
    *warnings, error = broken.stderr.splitlines()
    assert broken.returncode == 2 and all(w.startswith("gtsp-bench: warning: ") for w in warnings)
    assert error.startswith("gtsp-bench: error: solver 'broken' is not available: No module named")


# ---------------------------------------------------------------------- import cycles
def _project_modules() -> dict[str, Path]:
    """Dotted name -> file of every module of gtsp_bench and of solvers/ (gtsp_bench.solvers)."""
    modules = {}
    for root, package in ((REPO / "gtsp_bench", "gtsp_bench"), (REPO / "solvers", "gtsp_bench.solvers")):
        for path in sorted(root.rglob("*.py")):
            parts = [package, *path.relative_to(root).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts.pop()
            modules[".".join(parts)] = path
    return modules


class _Imports(ast.NodeVisitor):
    """Every import statement, at module level or in a function, but not under TYPE_CHECKING."""

    def __init__(self) -> None:
        self.found: list[ast.Import | ast.ImportFrom] = []

    def visit_If(self, node: ast.If) -> None:
        test = node.test
        if getattr(test, "id", None) == "TYPE_CHECKING" or getattr(test, "attr", None) == "TYPE_CHECKING":
            for child in node.orelse:
                self.visit(child)
        else:
            self.generic_visit(node)

    def visit_Import(self, node: ast.Import) -> None:
        self.found.append(node)

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        self.found.append(node)


def _import_graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (``from P import m`` counts as module P.m when
    there is one, else as P itself)."""
    modules = _project_modules()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        visitor = _Imports()
        visitor.visit(ast.parse(path.read_text(), filename=str(path)))
        targets: set[str] = set()
        for node in visitor.found:
            if isinstance(node, ast.Import):
                wanted = [alias.name for alias in node.names]
            else:
                base = node.module or ""
                if node.level:
                    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
                    for _ in range(node.level - 1):
                        package = package.rpartition(".")[0]
                    base = f"{package}.{base}" if base else package
                wanted = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
            for target in wanted:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name:
                    targets.add(target)
        graph[name] = targets
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One cycle through each back edge a depth-first search meets, as ``[a, b, ..., a]``."""
    state: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                found.append([*stack[stack.index(nxt):], nxt])
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)
    return found


def test_the_cycle_finder_finds_cycles():
    """The finder itself: a two-cycle and a three-cycle are named, a diamond is not a cycle."""
    assert _cycles({"a": {"b"}, "b": {"a"}}) == [["a", "b", "a"]]
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c", "a"]]
    assert _cycles({"a": {"b", "c"}, "b": {"d"}, "c": {"d"}, "d": set()}) == []


def test_import_graph_is_read_right():
    """A few edges known from the sources: relative and absolute, module level and in functions."""
    graph = _import_graph()
    assert "gtsp_bench.data.parse" in graph["gtsp_bench.data.io"]
    assert "gtsp_bench.data.gtsplib" not in graph["gtsp_bench.data.io"]
    assert "gtsp_bench.solvers.heuristics.greedy" in graph["gtsp_bench.solvers.exact.dp"]
    assert "gtsp_bench.report.paper" in graph["gtsp_bench.cli.bench"]  # imported inside a command function
    assert all(m.startswith("gtsp_bench") for targets in graph.values() for m in targets)


def test_no_import_cycles():
    """No project module imports itself back, directly or through others, at module level or in a
    function (a function-level cycle is a layering error that merely waits for its call)."""
    cycles = _cycles(_import_graph())
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)
