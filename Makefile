# Two entry points (see README): `make run` and `make test-all`. Each creates .venv when missing and
# installs what it needs: `run` the core (numpy, scipy, filterpy, matplotlib), `test-all` the
# extras the suite exercises. uv installs when it is on PATH, pip otherwise (USE_PIP=1 forces pip); both
# show their progress. `make lab` opens the lessons in JupyterLab with the project's kernel.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
# parallel test workers (pytest-xdist); JOBS=0 runs serially
JOBS   ?= 2
UV     := $(if $(USE_PIP),,$(shell command -v uv 2>/dev/null))
# the full install (every extra), which the targets below without a stamp of their own use
STAMP  := $(VENV)/.installed-dev

ifneq ($(UV),)
MKVENV  = $(UV) venv --python $(PYTHON) $(VENV)
# --compile-bytecode: uv leaves modules uncompiled (pip compiles them); a sandbox box cannot write
# bytecode into the read-only venv, so without it every box compiles scipy and filterpy again
INSTALL = VIRTUAL_ENV=$(VENV) $(UV) pip install --compile-bytecode --python $(BIN)/python
else
MKVENV  = $(PYTHON) -m venv $(VENV) && $(BIN)/python -m pip install --upgrade pip
INSTALL = $(BIN)/python -m pip install --progress-bar on
endif

.PRECIOUS: $(VENV)/.installed-%

.PHONY: run test test-all test-fast lab lint bench docs lessons-html wheel clean

$(BIN)/python:
	$(MKVENV)

# $(VENV)/.installed-EXTRA: gpsaccel (editable) with that extra; .installed-core: no extra
$(VENV)/.installed-%: pyproject.toml | $(BIN)/python
	@echo "make: installing gpsaccel$(if $(filter core,$*),,[$*]) into $(VENV) with $(if $(UV),uv,pip)"
	$(INSTALL) -e ".$(if $(filter core,$*),,[$*])"
	$(BIN)/python -m compileall -q -j 0 gpsaccel >/dev/null  # the editable package's own bytecode
	@if $(BIN)/python -c "import ipykernel" 2>/dev/null; then \
	    $(BIN)/python -m ipykernel install --sys-prefix --name python3 >/dev/null; fi
	touch $@

run: $(VENV)/.installed-core
	MPLBACKEND=Agg $(BIN)/gpsaccel run

# PYTEST_ARGS: more arguments for pytest (e.g. -k lesson)
PYTEST_ARGS ?=
# --dist loadscope: each module (and class) runs whole on one worker, so a module fixture (a graded
# class, a Monte Carlo ensemble, a sweep) is built once, not once per worker that got one of its
# tests (with --dist load the attack and coop classes were graded on both workers); tests/conftest.py
# makes each lesson a unit of its own and hands out the costliest units first (FIRST), so the two
# workers end together
XDIST = $(if $(filter-out 0,$(JOBS)),-n $(JOBS) --dist loadscope)
PYTEST = MPLBACKEND=Agg $(BIN)/python -m pytest -q $(XDIST)
# `make test-all` (the README's): the whole suite.  `make test`, the default while developing and
# CI's second Python (.ci/run): every test but the slow ones (notebooks executed, wheels, browsers,
# the docs site, whole reports drawn, big Monte Carlo, a hostile class's second backend), and of
# each slow kind one (tests/conftest.py KEPT)
test-all: $(VENV)/.installed-test
	$(PYTEST) $(PYTEST_ARGS)

test: $(VENV)/.installed-test
	$(PYTEST) -m "not slow" $(PYTEST_ARGS)

# the core's tests (the Kalman core, the calibration system, the package's shape) without the
# slow ones (notebooks, wheels, browsers, big Monte Carlo): under a minute on two idle cores
FAST_TESTS ?= tests/kalman tests/calibration tests/test_validation.py tests/test_layout.py \
              tests/test_packaging.py
test-fast: $(VENV)/.installed-test
	$(PYTEST) -m "not slow" $(FAST_TESTS)

# LAB_FLAGS: e.g. --no-browser, --port 8890.  As root (a container, a lab machine's image) JupyterLab
# refuses to start without --allow-root: it is added when `id -u` is 0.  The pre-save hook saves a
# lesson without its outputs, so opening and running one leaves `git status` clean (docs/lessons.md).
# JUPYTER_CONFIG_PATH: no "official Jupyter news?" prompt, as in `gpsaccel lab` (lessons/lab.py).
LAB_FLAGS ?=
LAB_ROOT  := $(if $(filter 0,$(shell id -u)),--allow-root,)
lab: $(STAMP)
	JUPYTER_CONFIG_PATH=gpsaccel/lessons/jupyter-config$${JUPYTER_CONFIG_PATH:+:$$JUPYTER_CONFIG_PATH} \
	$(BIN)/jupyter lab --notebook-dir=lessons \
	    --FileContentsManager.pre_save_hook=gpsaccel.lessons.pre_save $(LAB_ROOT) $(LAB_FLAGS)

# mypy over the whole package (issue 22): clean
MYPY_CLEAN := gpsaccel

# radon: no function above cyclomatic complexity 20 (grade D or worse; boolean operators count)
lint: $(VENV)/.installed-dev
	$(BIN)/ruff check .
	$(BIN)/mypy $(MYPY_CLEAN)
	@out="$$($(BIN)/radon cc -s -n D gpsaccel)"; if [ -n "$$out" ]; then echo "$$out"; \
	    echo "make lint: the functions above exceed cyclomatic complexity 20 (radon cc); split them"; \
	    exit 1; fi

# every benchmark; their tables are written into docs/benchmarks/ for the documentation
bench: $(VENV)/.installed-test
	MPLBACKEND=Agg $(BIN)/python benchmarks/run.py --markdown docs/benchmarks

# the documentation site, warnings as errors, in docs/_build/html (math typeset offline)
docs: $(VENV)/.installed-docs
	MPLBACKEND=Agg $(BIN)/python -m sphinx -W --keep-going -b html -q docs docs/_build/html
	@echo "make: docs in docs/_build/html/index.html"

lessons-html: $(VENV)/.installed-lessons
	MPLBACKEND=Agg $(BIN)/gpsaccel lessons --html out/lessons

# the wheel and the sdist, in dist/
wheel: | $(BIN)/python
	$(if $(UV),$(UV) build -o dist .,$(BIN)/python -m pip wheel --no-deps -w dist .)

clean:
	rm -rf out build dist docs/_build docs/_lessons *.egg-info .pytest_cache
