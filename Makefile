# The two commands of the README. Each does its own set-up on a fresh machine.
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test setup lint

setup:
	bash .ci/setup $(VENV)

## Main job: calibrate the bundled example session (both methods) into out/demo/.
demo: setup
	$(BIN)/contactcal demo --out out/demo

## Tests: lint, format check, then the whole pytest suite.
test: setup
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python -m pytest -q
