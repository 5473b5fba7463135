# dragposer-studio: `make run` opens the studio, `make test` runs the test suite.
# Both prepare the machine first (scripts/bootstrap.sh): system libraries, .venv, and
# `pip install -e '.[dev]'` whenever pyproject.toml changed.

SHELL := /bin/bash
VENV := .venv
CLI := $(VENV)/bin/dragposer-studio
# Extra pytest arguments, e.g. `make test PYTEST_ARGS=tests/engine/test_bvh.py`.
PYTEST_ARGS ?=

.PHONY: run test bootstrap

bootstrap:
	@scripts/bootstrap.sh

run: bootstrap
	@if $(CLI) gui --help >/dev/null 2>&1; then \
		exec $(CLI) gui; \
	else \
		echo "The gui subcommand is not available yet; the command line offers:"; \
		$(CLI) --help; \
	fi

# pytest exits 5 when it collects nothing; that is a failure too, said plainly.
test: bootstrap
	@rc=0; $(VENV)/bin/python -m pytest -q $(PYTEST_ARGS) || rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "make test: no tests were collected" >&2; fi; \
	exit $$rc
