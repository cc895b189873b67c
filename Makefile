# seecap: set-up, demo and tests. Everything installs from nothing into .venv.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# A CPU build of torch for machines without CUDA; the package itself accepts a range.
TORCH_PIN ?= torch==2.13.0
DEMO_DIR ?= demo-session

.PHONY: install demo test bench bench-quick lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/pip install "$(TORCH_PIN)"
	$(BIN)/pip install -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(BIN)/python -m davis_io.demo --out $(DEMO_DIR)

test: $(STAMP)
	$(BIN)/python -m pytest -q; status=$$?; \
	if [ $$status -eq 5 ]; then echo "make test: pytest collected no tests" >&2; exit 1; fi; \
	exit $$status

bench-quick: $(STAMP)
	$(BIN)/python tools/bench.py --quick

bench: $(STAMP)
	$(BIN)/python tools/bench.py

lint: $(STAMP)
	$(BIN)/pip install -q ruff
	$(BIN)/ruff check davis_io seenerf tools tests

clean:
	rm -rf $(VENV) $(DEMO_DIR) build *.egg-info
