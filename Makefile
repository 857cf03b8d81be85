# Set-up and everyday targets. Every target creates .venv when it is missing.
PY ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
export DRAKE_ALLOW_NETWORK := meshcat
export MPLBACKEND := Agg
# pytest caches its rewritten test modules as bytecode; without it every run rewrites them
# all again (collection 10 s instead of 5 s per process)
unexport PYTHONDONTWRITEBYTECODE

.PHONY: demo test test-fast test-core test-paper docs notebooks bench lint fmt clean system-deps

$(BIN)/python:
	@command -v $(PY) >/dev/null 2>&1 || { echo "need $(PY)"; exit 2; }
	$(PY) -m venv $(VENV)

# pyproject.toml declares ranges; constraints.txt pins the versions the project is tested with.
$(STAMP): pyproject.toml constraints.txt | $(BIN)/python system-deps
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -c constraints.txt -e '.[dev]'
	touch $(STAMP)

# Graphviz (for rendering DOT exports), EGL (headless Drake cameras) and Chromium with its
# WebDriver (the browser test of the demonstration page) come from Debian.
DEBS := graphviz libegl1 chromium chromium-driver
system-deps:
	@if ! command -v dot >/dev/null 2>&1 || ! ldconfig -p | grep -q libEGL.so.1 \
	    || ! command -v chromedriver >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $(DEBS) >/dev/null) \
	      || echo "warning: could not install $(DEBS)"; \
	  else echo "warning: install $(DEBS) (apt-get install -y $(DEBS))"; fi; \
	fi

# The flagship: SMP-MRO Case 3 in Drake (plan -> verify -> BT grown at run time -> youBot
# recovers from an unplanned obstacle), recorded as a self-contained Meshcat animation.
demo: $(STAMP)
	@mkdir -p build
	$(BIN)/tamp simulate smp-mro --case 3 --record build/case3.html
	@echo "recording: build/case3.html (open it in a browser)"

# Everything, as CI runs it: lint, types, then every test (simulations, notebooks, training,
# the wheel, the docs build) but the paper's whole narratives (`make test-paper`: each of their
# features has a shorter run here), one pytest worker per core; a test file stays on one
# worker (its fixtures, e.g. a local Ray, start once); then the core on Python 3.12 and 3.13.
PYTEST_WORKERS ?= auto
test: $(STAMP)
	$(BIN)/ruff check tamp tests benchmarks notebooks examples docs/hooks.py
	$(BIN)/ruff format --check tamp tests benchmarks notebooks examples docs/hooks.py
	$(BIN)/pyright --pythonpath $(BIN)/python
	$(BIN)/pytest -q -n $(PYTEST_WORKERS) --dist loadfile -m "not paper"
	$(MAKE) --no-print-directory test-core

# The paper's narratives end to end in Drake (Zhou et al. Fig. 8-10, Example 1: 3-5 min each).
test-paper: $(STAMP)
	$(BIN)/pytest -q -rP -n $(PYTEST_WORKERS) --dist loadfile -m paper

# The quick loop while editing: every test not marked slow (under a minute on 2 cores).
test-fast: $(STAMP)
	$(BIN)/pytest -q -m "not slow" -n $(PYTEST_WORKERS) --dist loadfile

# The light core (no Drake, no torch: pip install tamp-hrc) on every other supported Python:
# a fresh venv per version with only the core and the test runner, then the fast tests of
# the symbolic layers. A version whose interpreter is missing is skipped with a warning
# (an error under CI, where the machines have them).
CORE_PYTHONS ?= 3.12 3.13
CORE_TESTS := tests/world tests/ltl tests/demo tests/rg tests/bt tests/lots tests/refine \
	tests/verification tests/commands tests/test_schema.py tests/test_fileio.py \
	tests/test_perturbation.py tests/test_core_install.py
test-core: $(STAMP)
	@for v in $(CORE_PYTHONS); do \
	  py=""; for p in python$$v $$HOME/.pyenv/versions/$$v.*/bin/python; do \
	    if $$p -c "" 2>/dev/null; then py=$$p; break; fi; done; \
	  if [ -z "$$py" ]; then \
	    if [ -n "$$CI" ]; then echo "error: no python$$v"; exit 2; fi; \
	    echo "warning: no python$$v: its core tests are skipped"; continue; fi; \
	  venv=build/venv-core-$$v; \
	  if [ ! -f $$venv/.installed ]; then \
	    rm -rf $$venv && $$py -m venv --without-pip $$venv \
	    && $(BIN)/pip --python $$venv/bin/python install -q -c constraints.txt -e '.[test-core]' \
	    && touch $$venv/.installed || exit 1; fi; \
	  echo "core tests on $$($$venv/bin/python --version)"; \
	  $$venv/bin/python -m pytest -q -p no:cacheprovider -m "not slow" -n $(PYTEST_WORKERS) \
	    --dist loadfile $(CORE_TESTS) || exit 1; \
	done

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

# The docs site (mkdocs.yml), into build/site: strict, so a broken link, anchor or API
# reference fails it; docs/hooks.py writes the CLI reference, the JSON Schemas and the
# landing-page pictures (tests/test_docs.py builds it too, inside `make test`).
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# Re-execute every notebook in place and save it with its outputs (commit the result).
notebooks: $(STAMP)
	$(BIN)/python notebooks/execute.py

lint: $(STAMP)
	$(BIN)/ruff check tamp tests benchmarks notebooks examples docs/hooks.py
	$(BIN)/pyright --pythonpath $(BIN)/python

fmt: $(STAMP)
	$(BIN)/ruff format tamp tests benchmarks notebooks examples docs/hooks.py
	$(BIN)/ruff check --fix tamp tests benchmarks notebooks examples docs/hooks.py

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .hypothesis
