# gtsp-bench: `make bench` and `make test` set everything up on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# Clusters for `make bench` (a range 4..10 or a list 4,7); the paper's K = 4..10 by default.
K      ?= 4..10
# More runner options, e.g. BENCH_ARGS="--solvers greedy,aco --jobs 2" (gtsp-bench bench --help).
BENCH_ARGS ?=
SUITE_ARGS ?=

.PHONY: install test lint docs bench bench-quick bench-exact bench-heuristics bench-drl bench-glns clean

install: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check \
		-c constraints.txt -e '.[dev,gurobi,pyvrp,lkh]'
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check .

# The documentation site (mkdocs.yml, docs/) into site/; --strict turns broken links into errors.
docs: $(STAMP)
	$(BIN)/python -m mkdocs build --strict --site-dir site

# `python -m` runs this checkout's code whichever checkout the venv was installed from.
bench: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench -K $(K) $(BENCH_ARGS)

bench-quick: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench --quick $(BENCH_ARGS)

# The side-by-side suites (gtsp-bench bench --suite NAME; rows in benchmarks/out/NAME.csv):
# QUICK=1 for the quick preset, SUITE_ARGS for more options (gtsp-bench bench --help).
bench-exact: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench --suite exact $(if $(QUICK),--quick) $(SUITE_ARGS)

bench-heuristics: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench --suite heuristics $(if $(QUICK),--quick) $(SUITE_ARGS)

bench-drl: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench --suite learned $(if $(QUICK),--quick) $(SUITE_ARGS)

# lns against GLNS on its 45 GTSPLIB instances (benchmarks/glns.py --help; GLNS_ARGS for options,
# e.g. GLNS_ARGS="--seeds 3 --jobs 2", or "--large" for the 1,000-15,112-node files at 60 s).
GLNS_ARGS ?=
bench-glns: $(STAMP)
	$(BIN)/python benchmarks/glns.py $(GLNS_ARGS)

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build site *.egg-info
