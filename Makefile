# gtsp-bench: `make bench` and `make test` set everything up on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# Clusters for `make bench` (a range 4..10 or a list 4,7); the paper's K = 4..10 by default.
K      ?= 4..10
# More runner options, e.g. BENCH_ARGS="--solvers greedy,aco --jobs 2" (gtsp-bench bench --help).
BENCH_ARGS ?=

.PHONY: install test lint docs bench bench-quick bench-all train-local train-local-gpu clean

install: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check \
		-c constraints.txt -e '.[dev,gurobi,pyvrp,lkh,dask]'
	@echo "compiling lns's kernels once (numba, cached beside the module; about two minutes)"
	$(BIN)/python -c "from gtsp_bench.solvers.heuristics.lns_kernels import warm_up; warm_up()"
	$(BIN)/python -c "from gtsp_bench.solvers.exact.mip.flow import warm_up; warm_up()"
	$(BIN)/python -c "from gtsp_bench.proof.pairs import warm_up; warm_up()"
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
# The paper's experiments into results/paper (about 2 minutes on 2 cores; K=4..10 by default).
bench: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench paper -K $(K) $(BENCH_ARGS)

bench-quick: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench paper --quick $(BENCH_ARGS)

# Every named benchmark (gtsp-bench bench --list): `make bench-NAME` runs it into results/NAME;
# QUICK=1 for its quick variant (results/quick/NAME), BENCH_ARGS for more options.
bench-%: $(STAMP)
	$(BIN)/python -m gtsp_bench.cli bench $* $(if $(QUICK),--quick) $(BENCH_ARGS)

# Every committed table and figure, regenerated: the benchmarks whose outputs results/ and docs/
# hold (about 2 h 30 min on 2 cores, the sum of their full-run times in `gtsp-bench bench --list`;
# a rerun re-uses every finished solve). The three long ones are run on their own, with
# make bench-NAME: glns-large (about 2 h 10 min on one core), exact-frontier-uav (3 h) and
# exact-frontier (20 h, a few files at a time: docs/solvers/exact.md).
BENCH_ALL = paper heuristics-table learned learned-transfer glns lns-effort scale textbook exact-scale
bench-all: $(STAMP)
	status=0; for b in $(BENCH_ALL); do \
		$(BIN)/python -m gtsp_bench.cli bench $$b $(BENCH_ARGS) || status=1; done; exit $$status

# Train the local-view policy by imitating lns tours (the shipped checkpoints/local.pt; 33-45
# minutes on one core: labels, then 27 minutes of training). TRAIN_ARGS for more options.
TRAIN_ARGS ?=
train-local: $(STAMP)
	$(BIN)/python -m gtsp_bench.solvers.learned.imitation --recipe local \
		-o solvers/learned/checkpoints/local.pt $(TRAIN_ARGS)

# The widest policy on a GPU (the shipped checkpoints/local-l4.pt: an H200 with 16 cores; labels
# about 16 minutes on 2 CPU cores, or 3-4 on 15 processes; then 400 s of training).
train-local-gpu: $(STAMP)
	$(BIN)/python -m gtsp_bench.solvers.learned.imitation --recipe local-gpu-l4 --seed 2 \
		--device cuda --workers 15 -o solvers/learned/checkpoints/local-l4.pt $(TRAIN_ARGS)

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build site *.egg-info
