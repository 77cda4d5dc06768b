# Two commands on a fresh machine (Python 3.11, 3.12 or 3.13, and make):
#   make serve   - create .venv from the lock file if missing, run the service on HOST:PORT
#                  (environment or `make serve PORT=...`; default 127.0.0.1:8000, api/config.py)
#   make test    - create .venv (with test tools) if missing, run the whole suite
# The interpreter: the newest supported one on the PATH (PYTHON=... overrides; `make python`
# says which it is)
PYTHON ?= $(shell for p in python3.13 python3.12 python3.11 python3; do \
	$$p -c 'import sys; sys.exit(not (3, 11) <= sys.version_info < (3, 14))' 2>/dev/null \
	&& { echo $$p; break; }; done)
VENV   ?= .venv
BIN    := $(VENV)/bin
export OMP_NUM_THREADS ?= 1
export OPENBLAS_NUM_THREADS ?= 1

# the project itself, editable, built by the setuptools the lock pinned
INSTALL_SELF := $(BIN)/python -m pip install -qq --no-deps --no-build-isolation -e .

.PHONY: serve test long stress bench atlas lint lock lock-check notebook notebooks python clean

python:
	@test -n "$(PYTHON)" || { echo "make: no Python 3.11, 3.12 or 3.13 found (tried python3.13," \
		"python3.12, python3.11, python3): install one, or give its path as PYTHON=..." >&2; exit 1; }
	@echo $(PYTHON)

$(BIN)/python:
	@$(MAKE) --no-print-directory python >/dev/null
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"

$(VENV)/.runtime: requirements.lock pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --require-hashes -r requirements.lock
	$(INSTALL_SELF)
	touch $@

$(VENV)/.dev: requirements-dev.lock pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --require-hashes -r requirements-dev.lock
	$(INSTALL_SELF)
	touch $@ $(VENV)/.runtime

# JupyterLab on notebooks/, with a kernel of this environment (JUPYTER_ARGS: more options, e.g.
# --no-browser, or --allow-root where Jupyter runs as root)
JUPYTER_ARGS ?=
notebook: $(VENV)/.dev
	$(BIN)/python -m pip install --quiet --require-hashes -r requirements-notebook.lock
	$(BIN)/python -m ipykernel install --sys-prefix --name quickreturn-synth \
		--display-name "quickreturn-synth (.venv)"
	$(BIN)/jupyter lab $(JUPYTER_ARGS) notebooks/

# every compiled function a request can load (the analysis's, the motion search's) in the disk
# cache (SYNTH_CACHE, else ~/.cache/synth), built in a minute or two and again when synth's
# sources change: the service loads them as it starts, no request waits for a compiler
$(VENV)/.compiled: $(VENV)/.runtime $(shell find synth -name '*.py')
	$(BIN)/python -m synth.synthesis.warm
	touch $@

serve: $(VENV)/.runtime $(VENV)/.compiled
	$(BIN)/python -m api.serve

# the suite: all but the serial and the long tests on every core (pytest-xdist), then the serial
# ones alone (they time a live service, or answer within a budget that sharing the cores would
# cut); the long ones (tens of seconds each: the image, a fresh checkout, the quick benchmarks,
# the service under the heaviest loads) are `make long`'s, which CI runs after this
test: $(VENV)/.dev $(VENV)/.compiled
	$(BIN)/python -m pytest -q -n auto -m "not serial and not long"; a=$$?; \
	$(BIN)/python -m pytest -q -m "serial and not long"; b=$$?; exit $$(( a || b ))

long: $(VENV)/.dev $(VENV)/.compiled
	$(BIN)/python -m pytest -q -n auto -m "long and not serial"; a=$$?; \
	$(BIN)/python -m pytest -q -m "long and serial"; b=$$?; exit $$(( a || b ))

# the numerical-stability suite at full length (≥ 10 000 hypothesis cases per type and property)
# and the full global-search cross-check of the synthesis optima (≥ 20 targets per type), and
# the envelope against dense pin paths on more designs, the motion objectives' referee for the
# crank-rocker, the certified motion optima and least peak torques against brute-force draws
# (20 targets per type and objective, each load; the crank shaper's over its ram link too), the
# least peak torque against the independent global search (20 targets per type: the
# four-bars' referee takes 10-20 minutes a target, hours in all), and 5 000 loaded analyses
# and 500 loaded syntheses at the limits, and 1 000
# budgeted syntheses on the server, each within its budget (200 in `make test`)
stress: $(VENV)/.dev $(VENV)/.compiled
	HYPOTHESIS_PROFILE=stress $(BIN)/python -m pytest -q tests/referees/test_stress.py tests/referees/test_global_search.py \
		tests/referees/test_quality.py tests/referees/test_motion_search.py tests/referees/test_loaded_limits.py \
		tests/referees/test_certified.py tests/referees/test_certified_torque.py \
		tests/referees/test_certified_crank_shaper.py tests/referees/test_peak_torque.py
	SYNTH_BUDGET_REQUESTS=1000 $(BIN)/python -m pytest -q tests/service/test_budgets.py

# the design atlas the service ships (GET /v1/atlas) and the README's charts: docs/atlas/,
# resumed if interrupted; its summary goes to api/atlas.json, the one copy the service serves
atlas: $(VENV)/.dev
	$(BIN)/python -m synth.atlas --out docs/atlas --charts
	mv docs/atlas/atlas.json api/atlas.json

# run time against error, analysis cost, service latency: tables, benchmarks/results/*.json, plots
bench: $(VENV)/.dev $(VENV)/.compiled
	$(BIN)/python -m benchmarks

# the style and the types: ruff's lint and its format check over the repository, and mypy
# --strict over synth/ and api/ (pyproject.toml, [tool.mypy])
lint: $(VENV)/.dev
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy synth
	$(BIN)/mypy api

# Execute every notebook in place, outputs and all, as the repository carries them
notebooks: $(VENV)/.dev
	$(BIN)/python -m tests.support.notebooks

# Regenerate the lock files after changing pyproject.toml (needs uv: pip install uv): one lock
# for every supported Python (markers where they differ), with the setuptools that builds the
# project; the notebook lock is the dev lock's pins and JupyterLab's.
UV_COMPILE := uv pip compile --universal --python-version 3.11 --generate-hashes
lock:
	echo "setuptools>=77" | $(UV_COMPILE) pyproject.toml - -o requirements.lock
	echo "setuptools>=77" | $(UV_COMPILE) pyproject.toml - --extra dev -o requirements-dev.lock
	echo "setuptools>=77" | $(UV_COMPILE) pyproject.toml - --extra dev --extra notebook \
		-c requirements-dev.lock -o requirements-notebook.lock

# Whether each lock installs on each supported Python (Linux x86-64, wheels only): pip resolves
# it without installing (downloads what it has not cached)
LOCK_PYTHONS := 3.11 3.12 3.13
lock-check:
	for v in $(LOCK_PYTHONS); do for f in requirements*.lock; do \
		echo "Python $$v: $$f"; \
		$(PYTHON) -m pip install --quiet --dry-run --ignore-installed --only-binary=:all: \
			--implementation cp --python-version $$v --platform manylinux_2_28_x86_64 \
			--platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 \
			--target "$$(mktemp -d)" --require-hashes -r $$f || exit 1; done; done

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis
