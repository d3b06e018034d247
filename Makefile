# One source of truth for the commands: the README gives `make paper` and `make test`,
# and .ci/run calls `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
export PYO3_PYTHON := $(abspath $(BIN)/python)

.PHONY: setup paper study test test-rust test-python lint bench bench-rust clean

## setup: create .venv, install burstloc (building the Rust extension) with its dev/bench extras
# `pip install -e` runs maturin's PEP 660 editable build: the extension is compiled in release
# mode into python/burstloc/ and the Python sources are used in place. It reruns only when the
# Rust sources, a manifest or pyproject.toml changed (or the extension is missing), so a second
# `make setup` is instant; Python edits never need it.
PY_FOR_SUFFIX := $(shell test -x $(BIN)/python && echo $(BIN)/python || echo $(PYTHON))
EXT          := python/burstloc/_core$(shell $(PY_FOR_SUFFIX) -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
BUILD_INPUTS := pyproject.toml Cargo.toml $(wildcard Cargo.lock) \
                $(shell find crates -path '*/src/*.rs' -o -name Cargo.toml -o -name build.rs 2>/dev/null)

# The extension is compiled for the CPU of the machine that runs `make setup` (it is built
# where it runs): the vectorized bank and Shewhart loops run 2-5x faster than in a generic
# x86-64 build. Results are bit-identical (Rust neither fuses nor reorders float operations).
# `make setup EXT_RUSTFLAGS=` builds a portable extension.
EXT_RUSTFLAGS ?= -C target-cpu=native

setup: $(EXT) networks/todini6.inp
	scripts/install-mosquitto.sh

# A byte copy of one of WNTR's example networks, used by `burstloc study`: generated from the
# installed WNTR rather than shipped (it is a third-party file; see networks/README.md).
networks/todini6.inp: networks/build_wntr_examples.py $(EXT)
	$(BIN)/python networks/build_wntr_examples.py > /dev/null

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(EXT): $(BIN)/python $(BUILD_INPUTS)
	$(BIN)/python -m pip install -q --upgrade pip
	RUSTFLAGS="$(EXT_RUSTFLAGS)" $(BIN)/python -m pip install -q -e ".[dev,bench]"
	@touch $@

## paper: the main job, the paper's experiment on the shipped network, with the paper's rules
## and our fused localizer (the default of `burstloc evaluate`) side by side
paper: setup
	$(BIN)/burstloc evaluate networks/paper15.inp --localizer paper fused

## study: the robustness study of docs/beyond-the-paper.md, report in docs/study/ (~8 min on
## 2 cores once simulated; the first run simulates 196 bursts, about an hour more)
study: setup
	$(BIN)/burstloc study --out docs/study --workers 2

## test: every test and lint (Rust and Python)
test: setup lint test-rust test-python

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

test-python:
	$(BIN)/python -m pytest -q

## bench: Python-side benchmarks on fresh data (bindings vs pure Python vs River vs TSNet), then
## burstloc.river beside River's PageHinkley on River's annotated change-point datasets
bench: setup
	$(BIN)/python benches/bench_detectors.py
	$(BIN)/python -m burstloc.river

## bench-rust: criterion on fresh seeded traces, built for this CPU like the extension (in its
## own target dir, so the test builds are not invalidated)
bench-rust:
	RUSTFLAGS="$(EXT_RUSTFLAGS)" CARGO_TARGET_DIR=target-bench cargo bench -p cpd-core -- --warm-up-time 1 --measurement-time 2

clean:
	rm -rf $(VENV) target
