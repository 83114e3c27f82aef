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
# a quick representative (578 s, 9 min 38 s, on 2 cores from a fresh clone; the whole suite
# took 17 to 19 min); `make test-slow` is the rest of the sweeps and the multi-minute
# multi-process and packaging checks (about 10 min, estimated from the last full run's
# per-test times). The README's Tests section says what each holds.
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
