# dragposer-studio: `make run` opens the studio, `make test` runs the test suite.
# Both prepare the machine first (scripts/bootstrap.sh): system libraries, .venv, and
# `pip install -e '.[dev]'` whenever pyproject.toml changed.

SHELL := /bin/bash
VENV := .venv
CLI := $(VENV)/bin/dragposer-studio
# Extra pytest arguments, e.g. `make test PYTEST_ARGS=tests/engine/test_bvh.py`.
PYTEST_ARGS ?=
# pytest-xdist worker processes, one per core of the 2-core CI machine: the suite runs
# one test at a time on one core otherwise (its solves keep one torch thread). Each
# module's tests stay in one worker (--dist loadscope), so a module-scoped fixture (the
# shared-data sweeps) is built once. `make test PYTEST_WORKERS=0`: one process.
PYTEST_WORKERS ?= 2

.PHONY: run test check format bootstrap

bootstrap:
	@scripts/bootstrap.sh

run: bootstrap
	@if $(CLI) gui --help >/dev/null 2>&1; then \
		exec $(CLI) gui; \
	else \
		echo "The gui subcommand is not available yet; the command line offers:"; \
		$(CLI) --help; \
	fi

# Lint (ruff) and type check (mypy on engine/, as configured in pyproject.toml); no display
# needed. `make test` runs it first, so CI (.ci/run) fails on a lint or type error.
check: bootstrap
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/mypy

# Reformat the tree with ruff's formatter ([tool.ruff.format] in pyproject.toml).
format: bootstrap
	$(VENV)/bin/ruff format .

# pytest exits 5 when it collects nothing; that is a failure too, said plainly.
test: bootstrap check
	@rc=0; $(VENV)/bin/python -m pytest -q -n $(PYTEST_WORKERS) --dist loadscope $(PYTEST_ARGS) || rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "make test: no tests were collected" >&2; fi; \
	exit $$rc
