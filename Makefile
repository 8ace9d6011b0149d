# The two commands a newcomer needs: `make run` and `make test` (see README.md).
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test test-slow test-lowest bench clean lint typecheck wheel-check

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

# `make run PORT=8080` (HOST=0.0.0.0 to listen on every interface)
HOST ?= 127.0.0.1
PORT ?= 8000
run: $(STAMP)
	$(VENV)/bin/rotordiag serve --host $(HOST) --port $(PORT)

# Two pytest-xdist workers (one per core of the development machine); a test file stays on one
# worker (--dist loadfile), so its module-scoped servers and clusters start once.
TEST_WORKERS ?= 2
PYTEST_PARALLEL := -n $(TEST_WORKERS) --dist loadfile

test: $(STAMP)
	$(VENV)/bin/pytest -q $(PYTEST_PARALLEL)

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

# The quick tests against the LOWEST declared versions: every direct dependency pinned to its
# floor in pyproject.toml (.ci/lowest_constraints.py writes `name==floor`; transitive ones resolve
# to their newest), in a separate venv. Fails if the floors do not install together or a test fails.
LOWEST_VENV ?= .venv-lowest
test-lowest: $(STAMP)
	rm -rf $(LOWEST_VENV)
	$(PYTHON) -m venv $(LOWEST_VENV)
	$(LOWEST_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(PY) .ci/lowest_constraints.py > $(LOWEST_VENV)/constraints.txt
	$(LOWEST_VENV)/bin/python -m pip install --quiet -c $(LOWEST_VENV)/constraints.txt -e '.[dev]'
	$(LOWEST_VENV)/bin/python -m pip check
	ROTORDIAG_EXPECT_FLOORS=1 $(LOWEST_VENV)/bin/pytest -q $(PYTEST_PARALLEL)

test-slow: $(STAMP)
	$(VENV)/bin/pytest -q -m slow

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b; done

clean:
	rm -rf $(VENV) $(LOWEST_VENV) .pytest_cache

# Rebuild the shipped default model (models/default_registry) from scratch with the
# project's own pipeline: simulate the seventeen dataset specs of DEFAULT_PARTS (resumable; about 39 min for the
# lumped parts and 12 min for the shaft trains on 2 cores), then evaluate on held-out plants, fit and register
# (about 23 min). See docs/models.md, "The shipped model".
.PHONY: default-model
DEFAULT_DATA ?= data/default
# the training parts of the shipped model, in the order the model was trained on them (models/default/dataset_<part>.toml)
DEFAULT_PARTS = aligned presets_aligned misaligned presets severe misaligned_more aligned_more misaligned_more2 aligned_more2 misaligned_more3 aligned_more3 bearings bearings_aligned trains_2pole trains_2pole_aligned trains_4pole trains_4pole_aligned
default-model: $(STAMP)
	mkdir -p $(DEFAULT_DATA)
	for part in $(DEFAULT_PARTS); do \
		$(VENV)/bin/rotordiag dataset generate models/default/dataset_$$part.toml --out $(DEFAULT_DATA)/$$part.h5 --no-progress || exit 1; \
	done
	rm -rf models/default_registry.new && mkdir models/default_registry.new
	# the shipped history comes along, so the new model takes the next version name (an asset's stored verdicts
	# name the version that answered them; a name is never given to a second model)
	cp models/default_registry/history.json models/default_registry.new/ 2>/dev/null || true
	$(VENV)/bin/rotordiag train $(foreach part,$(DEFAULT_PARTS),$(DEFAULT_DATA)/$(part).h5) --config models/default/train.toml --registry models/default_registry.new
	rm -rf models/default_registry && mv models/default_registry.new models/default_registry
