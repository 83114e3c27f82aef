# Two commands on a fresh machine: `make demo` (the high five in simulation) and `make test`.
# Both create .venv and install what they need on first use.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: install demo test test-slow install-ros2 test-ros2 bench bench-full docs lint typecheck tsid

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
	$(BIN)/python -m pytest -q -m "not slow and not ros2"

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m "slow and not ros2"

# ROS 2 (docs/ros2.md): the ros2 extra's wheels into the same venv, then the interface packages
# (go2_interfaces, control_msgs) generated with rosidl into it (cached by the sources' hash),
# then the tests that need them (CI's third stage, after the two above ran without rclpy).
ROS2_STAMP := $(VENV)/.ros2-installed-stamp
$(ROS2_STAMP): $(STAMP) pyproject.toml
	$(BIN)/python -m pip install -q -e '.[test,scale,solvers,ros2]'
	touch $(ROS2_STAMP)

install-ros2: $(ROS2_STAMP)
	$(BIN)/python -m go2_ros2.interface_build

test-ros2: install-ros2
	$(BIN)/python -m pytest -q -m ros2 tests/ros2

bench: $(STAMP)
	$(BIN)/python -m benchmarks.qp_timing --quick

bench-full: $(STAMP)
	$(BIN)/python -m benchmarks.qp_timing

# Every picture the README and docs/ show, and the numbers they quote (docs/pictures.json):
# the high five's picture, GIF and plot (about a minute), then the QP benchmark and the
# plant-pushes sweep run again for theirs (several minutes more on 2 cores). The first three
# alone: `.venv/bin/python scripts/docs_media.py`.
docs: $(STAMP)
	$(BIN)/python scripts/docs_media.py --all

lint: $(STAMP)
	$(BIN)/python -m ruff check .

# mypy on the public modules (the facades and the modules whose names they export), as CI's
# tests/test_mypy_public.py runs it: 0 errors.
typecheck: $(STAMP)
	$(BIN)/python -m mypy --follow-imports=silent $$($(BIN)/python tests/public_modules.py)

# TSID for the benchmark's optional row (benchmarks/tsid_row.py), in its own environment: the
# registry has TSID's bindings but only libtsid's source, and the bindings built for another
# libtsid crash (glibc "malloc assertion failure"), so both are built here against Pinocchio
# 4.1 (not the project's 3.8, which PlaCo is built against). Nothing else uses it. About 35
# minutes of compiling on 2 cores; CMEEL_JOBS sets the parallel jobs.
TSID_VENV := .venv-tsid
CMEEL_JOBS ?= 2
$(TSID_VENV)/.installed-stamp:
	$(PYTHON) -m venv $(TSID_VENV)
	$(TSID_VENV)/bin/python -m pip install -q -U pip
	CMEEL_JOBS=$(CMEEL_JOBS) $(TSID_VENV)/bin/python -m pip install -q tsid==1.10.0
	$(TSID_VENV)/bin/python -m pip install -q "pin[build]==4.1.0" "eiquadprog[build]" \
		"libtsid[build]==1.10.0" cmeel-eigen "cmeel[build]" cmake scipy \
		--only-binary pin,eiquadprog,libtsid
	CMEEL_JOBS=$(CMEEL_JOBS) $(TSID_VENV)/bin/python -m pip install -q --force-reinstall \
		--no-deps --no-build-isolation --no-binary tsid tsid==1.10.0
	touch $@

tsid: $(TSID_VENV)/.installed-stamp
