# The two commands of the README: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test lint venv dev-venv clean client loadtest

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Runtime install (the demo). The compiled kernels are built into their on-disk cache
# here, once, so that a service's first answers (and each test worker) only load them.
WARM_UP := $(BIN)/python -c "from planner.warmup import warm_up; warm_up()"

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet -e .
	$(WARM_UP)
	touch $@

# Development install (tests, linters).
$(VENV)/.installed-dev: pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet -e '.[dev]'
	$(WARM_UP)
	touch $(VENV)/.installed $@

venv: $(VENV)/.installed
dev-venv: $(VENV)/.installed-dev

demo: $(VENV)/.installed
	$(BIN)/tactile demo

lint: $(VENV)/.installed-dev
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

test: lint
	$(BIN)/python -m pytest -q -n auto --dist worksteal --ignore=tests/app/test_api_fuzz.py
	# schemathesis names every operation's test alike, which parallel workers would run once
	$(BIN)/python -m pytest -q tests/app/test_api_fuzz.py

# Regenerate the committed HTTP client from the service's OpenAPI schema.
client: $(VENV)/.installed-dev
	$(BIN)/python -m tactile.client_gen

# A real `tactile serve` at 1 and 2 workers under a bounded locust fleet of robots.
loadtest: $(VENV)/.installed-dev
	$(BIN)/python -m tactile.loadtest --workers 1 2 --users 8 --seconds 30

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache .mypy_cache .hypothesis
