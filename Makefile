# Two commands on a fresh machine (only Python 3.11 and make needed):
#   make serve   - create .venv from the lock file if missing, run the service on $(HOST):$(PORT)
#   make test    - create .venv (with test tools) if missing, run the whole suite
PYTHON ?= python3.11
VENV   ?= .venv
HOST   ?= 127.0.0.1
PORT   ?= 8000
BIN    := $(VENV)/bin
export OMP_NUM_THREADS ?= 1
export OPENBLAS_NUM_THREADS ?= 1

.PHONY: serve test stress bench lint lock clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	# make the repository importable (synth, api) without building a package
	echo "$(CURDIR)" > "$$($(BIN)/python -c 'import sysconfig; print(sysconfig.get_path("purelib"))')/quickreturn-synth.pth"

$(VENV)/.runtime: requirements.lock | $(BIN)/python
	$(BIN)/python -m pip install --quiet --require-hashes -r requirements.lock
	touch $@

$(VENV)/.dev: requirements-dev.lock | $(BIN)/python
	$(BIN)/python -m pip install --quiet --require-hashes -r requirements-dev.lock
	touch $@ $(VENV)/.runtime

serve: $(VENV)/.runtime
	$(BIN)/python -m api.serve --host $(HOST) --port $(PORT)

test: $(VENV)/.dev
	$(BIN)/python -m pytest -q

# the numerical-stability suite at full length (≥ 10 000 hypothesis cases per type and property)
# and the full global-search cross-check of the synthesis optima (≥ 20 targets per type), and
# the envelope against dense pin paths on more designs, and the motion objectives' referee
# for the crank-rocker
stress: $(VENV)/.dev
	HYPOTHESIS_PROFILE=stress $(BIN)/python -m pytest -q tests/test_stress.py tests/test_global_search.py \
		tests/test_quality.py tests/test_motion_search.py

# run time against error, analysis cost, service latency: tables, benchmarks/results/*.json, plots
bench: $(VENV)/.dev
	$(BIN)/python -m benchmarks

lint: $(VENV)/.dev
	$(BIN)/ruff check .

# Regenerate the lock files after changing pyproject.toml (needs uv: pip install uv).
lock:
	uv pip compile pyproject.toml --python-version 3.11 --generate-hashes -o requirements.lock
	uv pip compile pyproject.toml --extra dev --python-version 3.11 --generate-hashes -o requirements-dev.lock

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis
