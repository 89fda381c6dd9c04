# Two entry points (see README): `make run` and `make test`. Each creates .venv when missing.
# `make lab` opens the lessons in JupyterLab with the project's kernel.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test lab lint bench lessons-html clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	$(BIN)/python -m ipykernel install --sys-prefix --name python3 >/dev/null
	touch $(STAMP)

run: $(STAMP)
	MPLBACKEND=Agg $(BIN)/gpsaccel run

test: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m pytest -q

# LAB_FLAGS: e.g. --no-browser, --port 8890, or --allow-root inside a container run as root.
LAB_FLAGS ?=
lab: $(STAMP)
	$(BIN)/jupyter lab --notebook-dir=lessons $(LAB_FLAGS)

# modules that type-check clean with mypy (issue 22); add a module here once it does
MYPY_CLEAN := gpsaccel/registry.py gpsaccel/kalman gpsaccel/check/findings.py \
	gpsaccel/check/linear.py gpsaccel/check/whole_filter.py gpsaccel/check/tracker.py \
	gpsaccel/check/report.py gpsaccel/check/student_filter.py gpsaccel/check/problems.py \
	gpsaccel/calibration/mistakes.py

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/mypy $(MYPY_CLEAN)

bench: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python benchmarks/run.py

lessons-html: $(STAMP)
	MPLBACKEND=Agg $(BIN)/gpsaccel lessons --html out/lessons

clean:
	rm -rf out build *.egg-info .pytest_cache
