# Two entry points, each doing all set-up on a fresh machine:
#   make demo   the main job: both paper scenes end to end (plots + summaries in out/paper)
#   make test   the test suite
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
STAMP   = $(VENV)/.installed

.PHONY: demo test venv clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	$(VENV)/bin/inerter compile    # the engine's kernels, once for this machine (about 2 min on 2 cores)
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/inerter paper --model fmu --out out/paper $(DEMO_ARGS)

test: $(STAMP)
	$(PY) -m pytest -q $(PYTEST_ARGS)

clean:
	rm -rf $(VENV) build out .pytest_cache
