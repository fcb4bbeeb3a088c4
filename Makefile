# lfdfuse: `make demo` and `make test` do everything on a fresh machine.
VENV ?= .venv
PY := $(VENV)/bin/python
LFD := $(VENV)/bin/lfdfuse
DEMO := build/demo

.PHONY: demo test lint bench sample-logs install clean

$(VENV)/.installed: pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[dev]'
	touch $@

install: $(VENV)/.installed

demo: install
	@mkdir -p $(DEMO)
	$(LFD) worlds
	$(LFD) simulate --world building --teacher keep-left --duration 240 --seed 1 -o $(DEMO)/demo.mcap
	$(LFD) inspect $(DEMO)/demo.mcap

test: install
	$(PY) -m pytest

lint: install
	$(VENV)/bin/ruff format --check lfdfuse tests
	$(VENV)/bin/ruff check lfdfuse tests
	$(VENV)/bin/mypy

bench: install
	$(PY) -m lfdfuse.bench --out build/bench.json

sample-logs: install
	$(PY) -m lfdfuse.samples sample_logs

clean:
	rm -rf build
