# Set-up and everyday targets. Every target creates .venv when it is missing.
PY ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
export DRAKE_ALLOW_NETWORK := meshcat
export MPLBACKEND := Agg

.PHONY: demo test test-fast bench lint fmt clean system-deps

$(BIN)/python:
	@command -v $(PY) >/dev/null 2>&1 || { echo "need $(PY)"; exit 2; }
	$(PY) -m venv $(VENV)

# pyproject.toml declares ranges; constraints.txt pins the versions the project is tested with.
$(STAMP): pyproject.toml constraints.txt | $(BIN)/python system-deps
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -c constraints.txt -e '.[dev,campaign]'
	touch $(STAMP)

# Graphviz (for rendering DOT exports) and EGL (headless Drake cameras) come from Debian.
system-deps:
	@if ! command -v dot >/dev/null 2>&1 || ! ldconfig -p | grep -q libEGL.so.1; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq graphviz libegl1 >/dev/null) \
	      || echo "warning: could not install graphviz/libegl1"; \
	  else echo "warning: install graphviz and libegl1 (apt-get install -y graphviz libegl1)"; fi; \
	fi

# The flagship: SMP-MRO Case 3 in Drake (plan -> verify -> BT grown at run time -> youBot
# recovers from an unplanned obstacle), recorded as a self-contained Meshcat animation.
demo: $(STAMP)
	@mkdir -p build
	$(BIN)/tamp simulate smp-mro --case 3 --record build/case3.html
	@echo "recording: build/case3.html (open it in a browser)"

# Everything, as CI runs it: lint, then every test (simulations, notebooks, training, the wheel),
# one pytest worker per core; a test file stays on one worker (its fixtures, e.g. a local Ray,
# start once).
PYTEST_WORKERS ?= auto
test: $(STAMP)
	$(BIN)/ruff check tamp verification tests benchmarks
	$(BIN)/ruff format --check tamp verification tests benchmarks
	$(BIN)/pytest -q -n $(PYTEST_WORKERS) --dist loadfile

# The quick loop while editing: every test not marked slow (under a minute on 2 cores).
test-fast: $(STAMP)
	$(BIN)/pytest -q -m "not slow" -n $(PYTEST_WORKERS) --dist loadfile

# Every benchmark, each side by side with its peer (the Fast Downward comparison alone takes
# about 20 minutes because the peer runs into its 300 s limit at n >= 10).
bench: $(STAMP)
	$(BIN)/pip install -q -c constraints.txt -e '.[dev,campaign,bench]'
	$(BIN)/python benchmarks/rg_vs_planner.py
	$(BIN)/python benchmarks/bt_tick.py
	$(BIN)/python benchmarks/lots_vs_product.py
	$(BIN)/python benchmarks/verify.py
	$(BIN)/python benchmarks/sim_smp.py
	$(BIN)/python benchmarks/grasp.py
	$(BIN)/python benchmarks/refine.py
	$(BIN)/python benchmarks/campaign.py

lint: $(STAMP)
	$(BIN)/ruff check tamp verification tests benchmarks

fmt: $(STAMP)
	$(BIN)/ruff format tamp verification tests benchmarks
	$(BIN)/ruff check --fix tamp verification tests benchmarks

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .hypothesis
