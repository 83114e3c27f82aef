# Two commands on a fresh machine: `make demo` (the high five in simulation) and `make test`.
# Both create .venv and install what they need on first use.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: install demo test test-slow bench bench-full docs lint

$(STAMP): pyproject.toml scripts/setup.sh
	PYTHON=$(PYTHON) bash scripts/setup.sh
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(BIN)/go2-wbc high-five

# The suite in two stages (both run by CI, .ci/run): `make test` is every area, each sweep by
# a quick representative (under 5 minutes on 2 cores from a fresh clone); `make test-slow` is
# the rest: the sweeps' other values, the multi-process and packaging checks, and the tests
# listed in tests/slow_stage.txt. The README's Tests section says what each holds and how long.
test: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow"

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow

bench: $(STAMP)
	$(BIN)/python -m benchmarks.qp_timing --quick

bench-full: $(STAMP)
	$(BIN)/python -m benchmarks.qp_timing

# The README's and docs/ pictures and the numbers they quote (docs/pictures.json).
docs: $(STAMP)
	$(BIN)/python scripts/docs_media.py

lint: $(STAMP)
	$(BIN)/python -m ruff check .
