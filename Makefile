# Two commands do all the set-up: `make run` and `make test` create .venv when it is missing.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin

.PHONY: run test bench lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Stamps re-install when pyproject.toml changes. The editable install puts the project folder on
# sys.path ("compat" mode): Dask workers put their scratch folder, which holds a "storage" spill
# folder, first on sys.path, and only a real path entry outranks that namespace folder.
INSTALL := $(BIN)/python -m pip install --quiet --config-settings editable_mode=compat -e

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(INSTALL) .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(INSTALL) '.[test]'
	touch $@ $(VENV)/.installed

# Ends with the report of the paper sweep; `eskin report` prints its path.
run: $(VENV)/.installed
	$(BIN)/eskin sweep --grid paper --root runs/paper
	$(BIN)/eskin report --root runs/paper

test: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q

bench: $(VENV)/.installed-test
	$(BIN)/python -m benchmarks

lint: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

clean:
	rm -rf $(VENV) runs .pytest_cache .hypothesis
