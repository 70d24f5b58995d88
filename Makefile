# Two entry points, each doing all set-up on a fresh machine:
#   make demo   the main job: both paper scenes end to end (plots + summaries in out/paper)
#   make test   the test suite
# The demo installs the package and what it runs on; the tests add the test extras on top.
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
# STAMP: the package, its dependencies and the compiled kernels; TEST_STAMP: the test extras too
STAMP      = $(VENV)/.installed
TEST_STAMP = $(VENV)/.installed-test
# the suite on two processes, a test file's tests in one (its module's shared runs computed once)
PYTEST_WORKERS ?= -n 2 --dist loadfile

.PHONY: demo test venv clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e .
	$(VENV)/bin/inerter compile    # the engine's kernels, once for this machine, then the builds of those a run enters (about 11 min on 2 cores)
	touch $(STAMP)

$(TEST_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(TEST_STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/inerter paper --model fmu --out out/paper $(DEMO_ARGS)

test: $(TEST_STAMP)
	$(PY) -m pytest -q $(PYTEST_WORKERS) $(PYTEST_ARGS)

clean:
	rm -rf $(VENV) build out .pytest_cache
