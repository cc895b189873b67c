# seecap: set-up, demo and tests. Everything installs from nothing into .venv.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# A CPU build of torch for machines without CUDA; the package itself accepts a range.
TORCH_PIN ?= torch==2.13.0
DEMO_DIR ?= demo-session
# Tools and tests run numpy as `seecap` does, without its huge-page advice (see davis_io/cli).
export NUMPY_MADVISE_HUGEPAGE ?= 0

.PHONY: install demo test fuzz browser bench bench-quick bench-blind bench-cluster bench-lens bench-sharing lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/pip install "$(TORCH_PIN)"
	$(BIN)/pip install -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

# The main job on the built-in default: the emulated camera recorded, then fitted end to end.
demo: $(STAMP)
	$(BIN)/seecap record --emulate room --exposure 0.15 --out $(DEMO_DIR) --overwrite
	$(BIN)/seecap fit $(DEMO_DIR) --preset fast --time-budget 10m

# One worker per core; a file's tests stay in one worker (its module fixtures are made once).
test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto --dist loadfile; status=$$?; \
	if [ $$status -eq 5 ]; then echo "make test: pytest collected no tests" >&2; exit 1; fi; \
	exit $$status

# Debian's Chromium (the report's browser test) and hdf5-tools (h5dump reads what seecap wrote);
# the suite leaves out only those two checks without them. Needs root (or sudo) and apt.
browser:
	apt-get install -y -q chromium chromium-driver hdf5-tools

# Every verb's parser driven by 500 hostile command lines each (the suite runs 100 of them).
fuzz: $(STAMP)
	SEECAP_FUZZ_EXAMPLES=500 $(BIN)/python -m pytest -q tests/test_cli_fuzz.py

bench-quick: $(STAMP)
	$(BIN)/python tools/bench.py --quick

# RAY=local (or a cluster's address) runs every rung and blind session as a Ray task.
RAY_OPTION = $(if $(RAY),--ray $(RAY))

bench: $(STAMP)
	$(BIN)/python tools/bench.py --publish $(RAY_OPTION)
	$(BIN)/python tools/bench_blind.py --jobs 2 --publish $(RAY_OPTION)
	$(BIN)/python tools/bench_lens.py --publish
	$(BIN)/python tools/bench_sharing.py --publish

# The blind-camera benchmark alone: fourteen randomly drawn sensors, each fitted from its recording.
bench-blind: $(STAMP)
	$(BIN)/python tools/bench_blind.py --jobs 2 --publish $(RAY_OPTION)

# The quick plan locally, then on a local Ray instance: wall times and scores side by side.
bench-cluster: $(STAMP)
	$(BIN)/python tools/bench_cluster.py --publish

# One scene through an undistorted and a distorted lens: the lens known, estimated or ignored.
bench-lens: $(STAMP)
	$(BIN)/python tools/bench_lens.py --publish

# A fit's training speed alone and beside one busy process (the threads it chooses, every core).
bench-sharing: $(STAMP)
	$(BIN)/python tools/bench_sharing.py --publish

lint: $(STAMP)
	$(BIN)/pip install -q ruff
	$(BIN)/ruff check davis_io seenerf tools tests

clean:
	rm -rf $(VENV) $(DEMO_DIR) build *.egg-info
