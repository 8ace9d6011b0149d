# The two commands a newcomer needs: `make run` and `make test` (see README.md).
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test test-slow bench clean lint typecheck wheel-check

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/rotordiag serve

test: $(STAMP)
	$(VENV)/bin/pytest -q

# ruff (lint + import order) and mypy. mypy reads the packages through build/typecheck/rotordiag,
# a tree of symlinks that gives the top-level folders their import names (rotordiag.simulator, ...).
lint: $(STAMP) typecheck
	$(VENV)/bin/ruff check .

typecheck: $(STAMP)
	mkdir -p build/typecheck/rotordiag
	ln -sfn ../../../rotordiag/__init__.py build/typecheck/rotordiag/__init__.py
	ln -sfn ../../../rotordiag/cli.py build/typecheck/rotordiag/cli.py
	ln -sfn ../../../rotordiag/core build/typecheck/rotordiag/core
	for p in simulator features models service; do ln -sfn ../../../$$p build/typecheck/rotordiag/$$p; done
	$(VENV)/bin/mypy

# Build the wheel, install it into a fresh venv outside the checkout and run simulate,
# diagnose and serve from there (see .ci/wheel-check).
wheel-check: $(STAMP)
	bash .ci/wheel-check

test-slow: $(STAMP)
	$(VENV)/bin/pytest -q -m slow

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b; done

clean:
	rm -rf $(VENV) .pytest_cache

# Rebuild the shipped default model (models/default_registry) from scratch with the
# project's own pipeline: simulate the three dataset specs (resumable; ~1.5 h on 2 cores),
# then evaluate on held-out plants, fit and register. See docs/models.md.
.PHONY: default-model
DEFAULT_DATA ?= data/default
default-model: $(STAMP)
	mkdir -p $(DEFAULT_DATA)
	$(VENV)/bin/rotordiag dataset generate models/default/dataset_aligned.toml --out $(DEFAULT_DATA)/aligned.h5 --no-progress
	$(VENV)/bin/rotordiag dataset generate models/default/dataset_misaligned.toml --out $(DEFAULT_DATA)/misaligned.h5 --no-progress
	$(VENV)/bin/rotordiag dataset generate models/default/dataset_bands.toml --out $(DEFAULT_DATA)/bands.h5 --no-progress
	rm -rf models/default_registry.new
	$(VENV)/bin/rotordiag train $(DEFAULT_DATA)/aligned.h5 $(DEFAULT_DATA)/misaligned.h5 $(DEFAULT_DATA)/bands.h5 --config models/default/train.toml --registry models/default_registry.new
	rm -rf models/default_registry && mv models/default_registry.new models/default_registry
