# Two commands do all the set-up: `make run` and `make test` create .venv when it is missing.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin

.PHONY: run test test-quick bench lint docs lock clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Stamps re-install when pyproject.toml or the lock changes. Dependencies come from the lock (the
# tested versions, run and test alike): it pins every package, so nothing is resolved again
# (--no-deps: 71 s instead of 111 s) and `pip check` then proves the set complete and consistent.
# pip installs one package at a time, on one core: two pip processes take every other line of the
# lock each (no package in both, none that needs another installed first), which took 27-44 s
# where one took 43-62 s (two rounds each, side by side).
# Bytecode is compiled at install, as pip does but on every core (54 s in all instead of 71 s):
# where PYTHONDONTWRITEBYTECODE is set no process writes it, and every sweep's workers would
# compile torch's modules again. The packages' own test folders (62 of 318 MB of sources) are
# never imported and are left out (29 s instead of 33 s). As with pip, a file that does not
# compile (torch ships one in a newer Python's syntax) is skipped: it is never imported here.
# The editable install puts the project folder on sys.path ("compat" mode): Dask workers put their
# scratch folder, which holds a "storage" spill folder, first on sys.path, and only a real path
# entry outranks that namespace folder. It builds with the lock's setuptools, already installed
# (--no-build-isolation: 1.4 s instead of 3.3 s, which went to a throw-away build environment).
# Numba's kernels are compiled into their disk cache (KERNELS) while compileall runs: on an empty
# cache, the processes a sweep or the suite starts at once would each compile the same kernels
# (a fresh clone's suite: 611 s against 560 s with the cache full, side by side); the fill alone
# keeps one core busy for about 10 s.
KERNELS := $(BIN)/python -m pipeline.run.kernel_cache
LOCK := requirements.lock
PIP := $(BIN)/python -m pip install --quiet --no-deps --no-compile
SITE = $$($(BIN)/python -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
HALF = grep -v '^\#' $(LOCK) | awk 'NR % 2 == $(1)' > $(VENV)/lock.$(1)
INSTALL := $(call HALF,0) && $(call HALF,1) \
	&& { $(PIP) -r $(VENV)/lock.0 & first=$$!; $(PIP) -r $(VENV)/lock.1; second=$$?; \
		wait $$first && [ $$second -eq 0 ]; } \
	&& $(PIP) --no-build-isolation --config-settings editable_mode=compat -e . \
	&& $(BIN)/python -m pip check --quiet \
	&& { $(KERNELS) & kernels=$$!; \
		$(BIN)/python -m compileall -q -q -j 0 -x '/tests?/' "$(SITE)"; wait $$kernels; }

# The project's own modules are compiled before every run and test run (a fraction of a second;
# only what changed), as the packages are at install: where PYTHONDONTWRITEBYTECODE is set, each
# of the hundreds of processes a sweep or the suite starts (commands, Dask workers) would compile
# them again. (Letting every process write what it compiles, instead of compiling at install,
# cost the suite more: its first processes all compiled the same packages at once.) The suite
# then fills the kernel cache again: a kernel whose source changed since is compiled once, not
# in every process (1 s when nothing changed).
COMPILE := $(BIN)/python -m compileall -q -q flows pipeline storage benchmarks

$(VENV)/.installed: pyproject.toml $(LOCK) | $(BIN)/python
	$(INSTALL)
	touch $@

$(VENV)/.installed-test: pyproject.toml $(LOCK) | $(BIN)/python
	$(INSTALL)
	touch $@ $(VENV)/.installed

# Sweeps the paper grid and ends with its report, whose path it prints. The local Prefect server
# it starts keeps the run's history for the UI and stops by itself after 30 idle minutes
# (`.venv/bin/eskin server stop` stops it now).
run: $(VENV)/.installed
	$(COMPILE)
	$(BIN)/eskin sweep --grid paper --root runs/paper --report

# The suite on TEST_WORKERS pytest-xdist workers: a module runs on one worker, in order, and the
# modules go out longest first (tests/conftest.py). The ten slowest tests are listed at the end.
# test-quick leaves the slow tests out. Three workers on two cores: with two, the suite's
# processes kept the cores only 129 % busy (end-to-end tests wait on server start-ups, polls and
# subprocesses); a third fills those waits (181 %, 8:46 against 12:00 on one loaded machine).
TEST_WORKERS ?= 3
PYTEST := $(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile --no-loadscope-reorder

test: $(VENV)/.installed-test
	$(COMPILE)
	$(KERNELS)
	$(PYTEST)

test-quick: $(VENV)/.installed-test
	$(COMPILE)
	$(KERNELS)
	$(PYTEST) -m "not slow"

bench: $(VENV)/.installed-test
	$(COMPILE)
	$(BIN)/python -m benchmarks

# The documentation site: docs/_build/html/index.html. Warnings (a broken reference, a notebook
# cell that fails) are errors; the tutorial notebook runs on every build.
# Importing the API for its pages imports Prefect: its state, like that of Dask, matplotlib and
# the notebook kernel, stays under docs/_build.
DOCS_STATE := docs/_build/.state
docs: $(VENV)/.installed-test
	mkdir -p $(DOCS_STATE)
	PREFECT_HOME=$(CURDIR)/$(DOCS_STATE)/prefect MPLCONFIGDIR=$(CURDIR)/$(DOCS_STATE)/mpl \
	DASK_TEMPORARY_DIRECTORY=$(CURDIR)/$(DOCS_STATE)/dask PREFECT_SERVER_ANALYTICS_ENABLED=false \
	DO_NOT_TRACK=1 IPYTHONDIR=$(CURDIR)/$(DOCS_STATE)/ipython \
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

lint: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

# Refreshes requirements.lock: pyproject.toml resolved in a throwaway venv; refuses a CUDA torch.
# setuptools is kept (torch requires it at run time, and the install resolves nothing).
lock:
	set -e; tmp=$$(mktemp -d); trap 'rm -rf "$$tmp"' EXIT; \
	$(PYTHON) -m venv "$$tmp/venv"; \
	"$$tmp/venv/bin/python" -m pip install --quiet --upgrade pip; \
	"$$tmp/venv/bin/python" -m pip install --quiet '.[test,docs]'; \
	{ grep '^#' $(LOCK) || true; "$$tmp/venv/bin/python" -m pip freeze --all --exclude eskin-sweep \
		--exclude pip --exclude wheel; } > "$$tmp/lock"; \
	if grep -qi '^nvidia-' "$$tmp/lock" || ! grep -q '^torch==.*+cpu$$' "$$tmp/lock"; then \
		echo "make lock: torch resolved to a CUDA build; give pip the CPU wheel" >&2; exit 1; fi; \
	mv "$$tmp/lock" $(LOCK)

clean:
	rm -rf $(VENV) runs .pytest_cache .hypothesis docs/_build docs/jupyter_execute docs/reference/generated
