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

.PHONY: install test lint docs bench bench-quick bench-exact bench-heuristics bench-heuristics-table bench-drl bench-learned train-local bench-glns bench-sets bench-scale clean

install: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check \
		-c constraints.txt -e '.[dev,gurobi,pyvrp,lkh,dask]'
	@echo "compiling lns's kernels once (numba, cached beside the module; about a minute)"
	$(BIN)/python -c "from gtsp_bench.solvers.heuristics.lns_kernels import warm_up; warm_up()"
	$(BIN)/python -c "from gtsp_bench.solvers.exact.mip.flow import warm_up; warm_up()"
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

# Every heuristic and peer on GTSPLIB by size and on UAV instances of K = 20..200, into the generated
# block of docs/solvers/heuristics.md; TABLE_ARGS="--time-limit 30 --per-group 5" (--help for more).
TABLE_ARGS ?=
bench-heuristics-table: $(STAMP)
	$(BIN)/python -m gtsp_bench.bench.heuristics_table $(TABLE_ARGS)

bench-drl: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench --suite learned $(if $(QUICK),--quick) $(SUITE_ARGS)

# Every learned policy (greedy as the baseline) from K = 4 to 200: mean gap per K and ms per
# instance (gtsp_bench/learned_table.py; LEARNED_ARGS for options, e.g. LEARNED_ARGS="--clusters 4,20").
LEARNED_ARGS ?=
bench-learned: $(STAMP)
	$(BIN)/python -m gtsp_bench.bench.learned_table $(LEARNED_ARGS)

# Train the local-view policy by imitating lns tours (the shipped checkpoints/local.pt; about 45
# minutes on one core: labels, then 27 minutes of training). TRAIN_ARGS for more options.
TRAIN_ARGS ?=
train-local: $(STAMP)
	$(BIN)/python -m gtsp_bench.solvers.learned.imitation --recipe local \
		-o solvers/learned/checkpoints/local.pt $(TRAIN_ARGS)

# lns against GLNS on its 45 GTSPLIB instances (benchmarks/glns.py --help; GLNS_ARGS for options,
# e.g. GLNS_ARGS="--seeds 3 --jobs 2", or "--large" for the 1,000-15,112-node files at 60 s).
GLNS_ARGS ?=
bench-glns: $(STAMP)
	$(BIN)/python benchmarks/glns.py $(GLNS_ARGS)

# A sweep over instance sets (gtsp-bench bench --set; outputs in benchmarks/out/sets): SET names
# the set (gtsplib, a folder under instances/, a path), SET_ARGS passes more options.
SET ?= gtsplib
SET_ARGS ?=
bench-sets: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench --set $(SET) $(SET_ARGS)

# The scale experiment: the paper's solvers and ours on the committed UAV sets of K = 20..200
# against their reference.csv (outputs in results/scale; SCALE_ARGS passes more options).
SCALE_SETS = --set uav-K20-N20-s1 --set uav-K50-N20-s1 --set uav-K100-N20-s1 --set uav-K200-N20-s1
SCALE_ARGS ?=
bench-scale: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench $(SCALE_SETS) --solvers greedy,aco,drl,am,local,lns \
		--omegas 0.5 --instances 10 --time-limit 10 --out results/scale $(SCALE_ARGS)

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build site *.egg-info
