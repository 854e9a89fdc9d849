# The two commands a newcomer needs (README.md):
#   make demo   create .venv if missing, install with the locked versions, run the demo
#   make test   same setup, then lint, type-check and run the whole test suite
# Others: make lock (re-resolve constraints.txt), make bench, make fuzz, make clean.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
PYTEST_ARGS ?=

.PHONY: demo test lint lock bench fuzz docs clean replay-js

$(STAMP): pyproject.toml constraints.txt
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' \
		|| { echo "multiarm needs Python >= 3.11: run 'make PYTHON=python3.11 ...'"; exit 1; }
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check \
		-c constraints.txt -e ".[analysis,dev,docs,urdf]"
	@touch $(STAMP)

demo: $(STAMP)
	$(BIN)/multiarm demo

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: lint
	$(BIN)/python -m pytest -n 2 $(PYTEST_ARGS)

bench: $(STAMP)
	$(BIN)/python -m benchmarks

# The long fuzz campaign of the parsers (tests/fuzz): FUZZ_RUNS inputs per target,
# at most FUZZ_TIME seconds each, one target after the other (FUZZ_TARGETS: a
# comma-separated subset); figures to benchmarks/results/fuzz.{json,md} (the rows
# of targets not run are kept), findings to .fuzz/ and (their inputs) to
# tests/fuzz/crashes/<target>/, where the tests replay them. The test suite runs a short
# one, every target in one process (tests/fuzz/test_fuzz.py).
FUZZ_RUNS ?= 100000
FUZZ_TIME ?= 3600
FUZZ_TARGETS ?=
fuzz: $(STAMP)
	$(BIN)/python -m tests.fuzz.campaign --runs $(FUZZ_RUNS) --max-time $(FUZZ_TIME) \
		--targets "$(FUZZ_TARGETS)" --out benchmarks/results/fuzz --merge \
		--crashes tests/fuzz/crashes

# The documentation site (mkdocs.yml) into site/, warnings as errors.
docs: $(STAMP)
	$(BIN)/mkdocs build --strict

# The replay's viewer script (workcell/replay/static/replay.js, committed so that
# an install needs no Node.js): three.js and the page's code (workcell/replay/web/src)
# bundled by esbuild, both pinned by workcell/replay/web/package-lock.json. Run it
# after editing the viewer or bumping three; CI checks the committed file is its output.
REPLAY_WEB := workcell/replay/web
replay-js:
	cd $(REPLAY_WEB) && npm ci --no-audit --no-fund && npm run build
	cp $(REPLAY_WEB)/node_modules/three/LICENSE workcell/replay/static/three-LICENSE.txt

# Re-resolve every dependency and rewrite the lock (constraints.txt).
lock:
	rm -rf .lock-venv
	$(PYTHON) -m venv .lock-venv
	.lock-venv/bin/python -m pip install --quiet --disable-pip-version-check -e ".[analysis,dev,docs,urdf]"
	{ echo "# Lock file: exact versions for every install (make demo/test use it)."; \
	  echo "# Regenerate with 'make lock' after changing pyproject.toml."; \
	  .lock-venv/bin/python -m pip freeze --exclude-editable --all \
		| grep -v -E '^(pip|setuptools|wheel)=='; } > constraints.txt
	rm -rf .lock-venv

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache .hypothesis build *.egg-info
