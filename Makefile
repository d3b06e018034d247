# One source of truth for the commands: the README gives `make paper` and `make test`,
# and .ci/run calls `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
export PYO3_PYTHON := $(abspath $(BIN)/python)

# Another Python, found as a user's CI would: `python3.X` on PATH (e.g. a pyenv shim, if it
# runs), else the newest 3.X among pyenv's versions. $(call find_python,3.13)
PYENV_ROOT ?= $(HOME)/.pyenv
find_python = $(shell for p in "$$(command -v python$(1))" \
                $$(ls -d $(PYENV_ROOT)/versions/$(1).*/bin/python$(1) 2>/dev/null | sort -rV); do \
                  [ -n "$$p" ] && "$$p" -c 'import sys; assert "%d.%d" % sys.version_info[:2] == "$(1)"' \
                    2>/dev/null && echo "$$p" && break; done)
# The second Python the suite runs on: 3.13 with numpy 2 (`make test PYTHON313=/path/to/python3.13`
# names one).
PYTHON313  ?= $(call find_python,3.13)
# The plain-pip smoke test's Python: 3.12, which neither suite uses (`make test PYTHON312=...`).
PYTHON312  ?= $(call find_python,3.12)
VENV313 := .venv313
BIN313  := $(VENV313)/bin

.PHONY: setup services setup313 networks paper study test test-rust test-python test-python313 \
        test-pip lint bench bench-rust clean

## setup: create .venv (the default Python), build burstloc's wheel, install it with its
## sim/dev/bench/river/web extras
# One wheel for every Python: the extension uses CPython's stable ABI (abi3, Python >= 3.10), so
# maturin builds it once, here, and the same file is installed in .venv and in .venv313. The
# wheel is rebuilt when the Rust or Python sources, a manifest or pyproject.toml change (cargo
# recompiles only on Rust changes). The extension is also unpacked into python/burstloc/, so
# `PYTHONPATH=python .venv/bin/python` runs the sources in place.
WHEEL_DIR    := target/wheels
WHEEL_STAMP  := $(WHEEL_DIR)/.built
# (recipes that run after the wheel is built)
WHEEL         = $(firstword $(wildcard $(WHEEL_DIR)/burstloc-*-abi3-*.whl))
EXT          := python/burstloc/_core.abi3.so
BUILD_INPUTS := pyproject.toml Cargo.toml $(wildcard Cargo.lock) README.md \
                $(shell find crates -path '*/src/*.rs' -o -name Cargo.toml -o -name build.rs 2>/dev/null) \
                $(shell find python -name '*.py' -o -name '*.pyi' -o -name '*.mako' -o -name py.typed \
                  -o -path '*/web/static/*' -type f 2>/dev/null)
EXTRAS       := sim,dev,bench,river,web,incidents,gis

# The extension is compiled for the CPU of the machine that runs `make setup` (it is built
# where it runs): the vectorized bank and Shewhart loops run 2-5x faster than in a generic
# x86-64 build. Results are bit-identical (Rust neither fuses nor reorders float operations).
# `make setup EXT_RUSTFLAGS=` builds a portable wheel.
EXT_RUSTFLAGS ?= -C target-cpu=native

setup: $(VENV)/.installed networks/todini6.inp networks

## services: what the tests need beside Python (not the main job): Mosquitto, the MQTT broker the
## monitor's integration tests start on a loopback port, Debian's Chromium with its WebDriver,
## the browser the control-room page's tests drive, and PostgreSQL, whose server the incident
## store's tests start in a temporary directory; installed where missing (as root with apt-get),
## else named with the command that installs them
services:
	scripts/install-mosquitto.sh
	scripts/install-chromium.sh
	scripts/install-postgresql.sh

## networks: EPANET's Net1, Net2, Net3 and Anytown in networks/public/ (not committed), from the
## pinned epyt wheel on PyPI, every file checked against its pinned SHA-256 (standard library
## only; downloads once, a few seconds; see networks/README.md)
networks: networks/public/MANIFEST.json

networks/public/MANIFEST.json: networks/fetch_public.py
	$(PYTHON) networks/fetch_public.py
	@touch $@

## setup313: create .venv313 (Python 3.13, numpy 2) and install the same wheel there
setup313: $(VENV313)/.installed

# A byte copy of one of WNTR's example networks, used by `burstloc study`: generated from the
# installed WNTR rather than shipped (it is a third-party file; see networks/README.md).
networks/todini6.inp: networks/build_wntr_examples.py $(VENV)/.installed
	$(BIN)/python networks/build_wntr_examples.py > /dev/null

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip "maturin>=1.9.4,<2"

$(BIN313)/python:
	@test -n "$(PYTHON313)" || { echo "make: no Python 3.13 found: neither python3.13 on PATH \
	nor $(PYENV_ROOT)/versions/3.13*; install one (e.g. pyenv install 3.13) or run \
	make test PYTHON313=/path/to/python3.13" >&2; exit 1; }
	$(PYTHON313) -m venv $(VENV313)
	$(BIN313)/python -m pip install -q --upgrade pip

$(WHEEL_STAMP): $(BIN)/python $(BUILD_INPUTS)
	rm -f $(WHEEL_DIR)/burstloc-*.whl
	RUSTFLAGS="$(EXT_RUSTFLAGS)" $(BIN)/maturin build --release --quiet --out $(WHEEL_DIR) \
	    --interpreter $(BIN)/python
	unzip -o -q -j $(WHEEL_DIR)/burstloc-*-abi3-*.whl 'burstloc/_core.abi3.so' -d python/burstloc/
	@touch $@

# The wheel with its extras (their dependencies), then the wheel itself again: its version does
# not change between builds, so pip would keep a previous build.
$(VENV)/.installed: $(WHEEL_STAMP)
	$(BIN)/python -m pip install -q "$(WHEEL)[$(EXTRAS)]"
	$(BIN)/python -m pip install -q --no-deps --force-reinstall "$(WHEEL)"
	@touch $@

$(VENV313)/.installed: $(BIN313)/python $(WHEEL_STAMP)
	$(BIN313)/python -m pip install -q "$(WHEEL)[$(EXTRAS)]"
	$(BIN313)/python -m pip install -q --no-deps --force-reinstall "$(WHEEL)"
	$(BIN313)/python -c 'import numpy, sys; assert int(numpy.__version__.split(".")[0]) >= 2; \
	    print("Python", sys.version.split()[0], "numpy", numpy.__version__)'
	@touch $@

## paper: the main job, the paper's experiment on the shipped network, with the paper's rules
## and our fused localizer (the default of `burstloc evaluate`) side by side
paper: setup
	$(BIN)/burstloc evaluate networks/paper15.inp --localizer paper fused

## study: the robustness study of docs/beyond-the-paper.md, report in docs/study/ (~8 min on
## 2 cores once simulated; the first run simulates 196 bursts, about an hour more)
study: setup
	$(BIN)/burstloc study --out docs/study --workers 2

## test: every test and lint (Rust and Python); the Python suite on the default Python and on
## Python 3.13 with numpy 2; a plain pip install on Python 3.12 running the README's tour
test: setup setup313 services lint test-rust test-python test-python313 test-pip

lint:
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -- -D warnings
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python -m mypy
	$(BIN)/python -m mypy.stubtest burstloc._core

# Unit, golden, property, snapshot-interop and fuzz tests (fuzz: proptest's 256 cases per target;
# PROPTEST_CASES=100000 for a longer run), the gateway example's end-to-end tests, and the
# no_std + alloc build of the same.
test-rust:
	cargo test -p cpd-core
	cargo test -p cpd-core --no-default-features
	cargo test -p moc-core
	cargo test -p feed-text

test-python:
	$(BIN)/python -m pytest -q

# The installed wheel, not the sources, on Python 3.13 (the tests' own helpers come from tests/).
test-python313: setup313 networks/todini6.inp networks
	$(BIN313)/python -m pytest -q

# A plain `pip install 'burstloc-...whl[sim]'` in a fresh virtualenv on Python 3.12 (neither .venv
# nor .venv313: the path of a user without the Makefile), then the README's tour as written (the
# block after `<!-- tour -->`), in an empty directory with an empty cache (~2 min).
test-pip: $(WHEEL_STAMP)
	@test -n "$(PYTHON312)" || { echo "make: no Python 3.12 found: neither python3.12 on PATH \
	nor $(PYENV_ROOT)/versions/3.12*; install one (e.g. pyenv install 3.12) or run \
	make test PYTHON312=/path/to/python3.12" >&2; exit 1; }
	scripts/smoke-pip.sh "$(PYTHON312)" "$(abspath $(WHEEL))"

## bench: Python-side benchmarks on fresh data (bindings vs pure Python vs River vs TSNet), then
## burstloc.river beside River's PageHinkley on River's annotated change-point datasets
bench: setup
	$(BIN)/python benches/bench_detectors.py
	$(BIN)/python -m burstloc.river
	$(BIN)/python benches/bench_position.py

## bench-rust: criterion on fresh seeded traces, built for this CPU like the extension (in its
## own target dir, so the test builds are not invalidated)
bench-rust:
	RUSTFLAGS="$(EXT_RUSTFLAGS)" CARGO_TARGET_DIR=target-bench cargo bench -p cpd-core -- --warm-up-time 1 --measurement-time 2

clean:
	rm -rf $(VENV) $(VENV313) target $(EXT)
