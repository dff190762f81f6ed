# gtsp-bench: `make bench` and `make test` set everything up on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# Clusters for `make bench` (a range 4..10 or a list 4,7).
K      ?= 4..10

.PHONY: install test lint bench bench-quick bench-heuristics clean

install: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check \
		-c constraints.txt -e '.[dev,gurobi,pyvrp]'
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/gtsp-bench solvers

# Heuristics side by side (benchmarks/heuristics.py); QUICK=1 for a subset.
bench-heuristics: $(STAMP)
	$(BIN)/python benchmarks/heuristics.py $(if $(QUICK),--quick)

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info
