# The two commands a new user runs: `make demo` and `make test`.
VENV   ?= .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip
STAMP  := $(VENV)/.installed-stamp
export PIP_DISABLE_PIP_VERSION_CHECK := 1

.PHONY: install demo test test-fast bench property sysdeps clean

$(STAMP): pyproject.toml
	@test -x $(PY) || python3 -m venv $(VENV)
	$(PIP) install -q --no-compile -e '.[dev]'   # bytecode is written on first import, for what is imported
	$(PY) -c "from phantom_cad.calibration import fastcsv; fastcsv.compile()"   # numba's cache: once
	@touch $(STAMP)

install: $(STAMP)

# System tools the checks use (PrusaSlicer, urdfdom's check_urdf, Chromium, colcon and ament_cmake): Debian packages,
# installed when missing and we are root (as on CI); otherwise the tests that need
# them say so and skip, and the demo builds everything but the print estimates.
sysdeps:
	@bash .ci/sysdeps

demo: install sysdeps
	$(VENV)/bin/phantom-cad demo

# in TEST_JOBS processes (pytest-xdist; a test module stays in one, with its fixtures); each
# whole-hand build and power grasp is made once between them (tests/support/shared.py)
TEST_JOBS ?= 2
test: install sysdeps
	$(PY) -m pytest -n $(TEST_JOBS) --dist loadscope

# The tests not marked slow (no whole-hand build, no MuJoCo simulation of a hand, no browser, no
# slicing of whole hands, no property test, no command line run for seconds): about a minute, for
# while you work. `make test` runs them all (CI).
test-fast: install sysdeps
	$(PY) -m pytest -m "not slow"

bench: install
	$(PY) bench/run.py

# The property test on a large sample (make test runs 10 files): every file that validates builds.
# N files, default 200; about 15-30 s per file that validates (docs/reliability.md).
property: install
	PHANTOM_PROPERTY_EXAMPLES=$(or $(N),200) $(PY) -m pytest -q tests/export/test_validation_builds.py

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
