# lfdfuse: `make demo` and `make test` do everything on a fresh machine.
VENV ?= .venv
PY := $(VENV)/bin/python
LFD := $(VENV)/bin/lfdfuse
DEMO := build/demo

.PHONY: demo test warm fuzz lint bench sample-logs install clean paper

$(VENV)/.installed: pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[dev]'
	touch $@

install: $(VENV)/.installed

demo: install
	@mkdir -p $(DEMO)
	@echo "== 1. a keep-left demonstration in the default world, learned, run in another building (tee)"
	$(LFD) simulate --teacher keep-left --duration 240 --seed 1 -o $(DEMO)/left.mcap
	$(LFD) segment $(DEMO)/left.mcap --behaviors avoid,wander_left,wander_right,wall_attract_left,wall_attract_right,sonar_avoid
	$(LFD) estimate $(DEMO)/left.seg.mcap -o $(DEMO)/left.yaml
	$(LFD) execute $(DEMO)/left.yaml --world tee --start 1,9,0 --max-time 120 -o $(DEMO)/left-run.mcap --report $(DEMO)/left-run.json
	@echo "== 2. the paper's three-goal task (left to red, centre to green, right to blue), learned once, run from another start"
	$(LFD) simulate --teacher sample_logs/three-goals.task.yaml --duration 400 --seed 1 -o $(DEMO)/task.mcap
	$(LFD) segment $(DEMO)/task.mcap
	$(LFD) estimate $(DEMO)/task.seg.mcap -o $(DEMO)/task.yaml
	$(LFD) execute $(DEMO)/task.yaml --start 3.5,1.0,0.2 --max-time 300 -o $(DEMO)/task-run.mcap --report $(DEMO)/task-run.json
	@echo "Open $(DEMO)/*-run.mcap in Foxglove or Lichtblick: map, robot, laser and the fusion arrows (/lfd/overlay)."
	$(PY) -m tests.support.demo_check $(DEMO)

# one worker more than the cores (pytest-xdist; work stealing, so one long closed loop does not
# hold the rest back): a fifth of the suite is live tests waiting on the clock (DDS participants,
# Foxglove servers, terminals at 10-30 Hz), and the extra worker computes meanwhile
test: warm
	$(PY) -m pytest -n $$(( $$(nproc) + 1 )) --dist worksteal

# before the tests: byte-compiled (every command a test starts imports lfdfuse again, and where the
# environment says PYTHONDONTWRITEBYTECODE each would compile its sources, ~0.2 s of CPU a process),
# and numba's kernels compiled once into their cache, where each test process would compile them
# again (nothing runs when the cache holds them); the test modules collected once with bytecode
# written, so pytest's rewritten asserts are cached too (each worker would rewrite every test
# module again, about 3 s of CPU each); .ci/run does this beside the linter
warm: install
	$(PY) -m compileall -q lfdfuse tests > /dev/null
	$(PY) -m tests.support.warm
	PYTHONDONTWRITEBYTECODE= $(PY) -m pytest --collect-only -q -p no:cacheprovider > /dev/null

# the whole hostile corpus (tests/hostile; make test runs a sample of every class)
fuzz: install
	LFDFUSE_FUZZ=1 $(PY) -m pytest tests/hostile

lint: install
	$(VENV)/bin/ruff format --check lfdfuse tests
	$(VENV)/bin/ruff check lfdfuse tests
	$(VENV)/bin/mypy

# every suite (tests/bench); one, shorter: make bench BENCH_ARGS='--suite world --quick'
bench: install
	$(PY) -m tests.bench.run --out build/bench.json $(BENCH_ARGS)

sample-logs: install
	$(PY) -m tests.support.samples sample_logs

paper: install
	$(LFD) report -o build/paper

clean:
	rm -rf build
