# indoorloc: the README's two commands, and the developer targets around them.
#
#   make demo        set up (Debian + Python dependencies), build, run `indoorloc demo`
#   make test        set up, build once, run ctest + pytest + the outside C++ app
#   make test-asan   ctest suite and the Python property suite under AddressSanitizer + UBSan
#   make bench       speed benchmarks against peers (writes benchmarks/results/)
#   make reproduce   every table of the five papers at full size (reports/reproduce/report.{md,html,json})
#
# Runs as root on a fresh Debian 12 machine (apt-get installs what is missing); as another
# user it only checks and names the missing packages. Python packages go into .venv/.

SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
.DEFAULT_GOAL := test

PYTHON ?= python3
JOBS ?= 2
VENV := .venv
PY := $(VENV)/bin/python
PIP := $(PY) -m pip --disable-pip-version-check -q
BUILD_DIR := build/py
STAGE_DIR := build/stage
ASAN_DIR := build/asan
export CMAKE_BUILD_PARALLEL_LEVEL := $(JOBS)

# Debian packages: compilers, C++ libraries (Eigen, CGAL + GMP/MPFR/Boost, Ceres + glog/gflags +
# SuiteSparse, GoogleTest), Python headers/venv for the system interpreter, and the headless
# browser of the track viewer's test (chromium + its chromedriver, driven by selenium).
DEBIAN_PACKAGES := g++ make cmake python3-dev python3-venv \
  libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev \
  libceres-dev libgoogle-glog-dev libgflags-dev libsuitesparse-dev libgtest-dev libnanoflann-dev \
  chromium chromium-driver libsqlite3-dev
# Build requirements (installed into the venv because the build runs without isolation, so
# that one persistent build folder serves the wheel, ctest and the C++ install).
BUILD_REQUIREMENTS := "scikit-build-core>=0.10" "pybind11>=2.10" "cmake>=3.20" ninja

.PHONY: all demo reproduce test test-cpp test-python test-cpp-app test-asan test-asan-python bench deps deps-debian \
        deps-python install clean

all: test

deps: deps-debian deps-python

deps-debian:
	@missing=$$(for p in $(DEBIAN_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" != 0 ]; then echo "missing Debian packages (run as root or apt-get install): $$missing"; exit 1; fi; \
	  echo "apt-get install: $$missing"; \
	  apt-get update -qq; \
	  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	fi

$(PY):
	$(PYTHON) -m venv $(VENV)

deps-python: $(PY)
	$(PIP) install $(BUILD_REQUIREMENTS)

# One CMake configure (build/py) serves the wheel, ctest and the installed C++ package.
install: deps
	$(PIP) install --no-build-isolation \
	  -Cbuild-dir=$(BUILD_DIR) -Ccmake.define.INDOORLOC_BUILD_TESTS=ON \
	  ".[test]"

test-cpp: install
	ctest --test-dir $(BUILD_DIR) -j$(JOBS) --output-on-failure

test-python: install
	cd tests/python && ../../$(PY) -m pytest -q -c ../../pyproject.toml --rootdir ../.. .

# The outside app: install headers + library + CMake package to a staging prefix, then build
# examples/cpp_app with nothing but find_package(indoorloc) and run it.
test-cpp-app: install
	rm -rf $(STAGE_DIR) build/cpp_app
	$(VENV)/bin/cmake --install $(BUILD_DIR) --component indoorloc_dev --prefix $(STAGE_DIR)
	$(VENV)/bin/cmake -S examples/cpp_app -B build/cpp_app -G Ninja \
	  -DCMAKE_PREFIX_PATH=$(abspath $(STAGE_DIR)) >/dev/null
	$(VENV)/bin/cmake --build build/cpp_app
	./build/cpp_app/cpp_app
	# A site file written by the just-installed Python package, read and tracked on by C++ alone.
	$(PY) examples/cpp_app/export_walk.py survey build/cpp_app_site
	$(VENV)/bin/indoorloc --quiet site build build/cpp_app_site/survey -o build/cpp_app_site/site.db --no-coverage
	$(PY) examples/cpp_app/export_walk.py walk build/cpp_app_site
	./build/cpp_app/site_app build/cpp_app_site/site.db build/cpp_app_site/walk_events.txt

test: install
	$(MAKE) --no-print-directory test-cpp test-python test-cpp-app

demo: install
	$(VENV)/bin/indoorloc demo --out reports/demo

# Resumable: a finished paper section is kept (indoorloc reproduce --rerun PAPER to redo it).
reproduce: install
	$(VENV)/bin/indoorloc reproduce --out reports/reproduce

# ctest built with AddressSanitizer + UndefinedBehaviorSanitizer, then the Python property suite
# against an ASan/UBSan build of _core (build/asan-py). A dlopen()ed extension cannot bring the ASan
# runtime itself (it must be the first library loaded, to intercept malloc), so it is preloaded
# into the interpreter, with libstdc++ (python is a C program: without it ASan cannot resolve the
# real __cxa_throw at start-up and aborts at the first C++ exception, "CHECK failed:
# asan_interceptors.cpp:320"). detect_leaks=0 for Python only: CPython deliberately never frees its
# interned objects, caches and the modules' static state at exit, so LeakSanitizer would report
# thousands of leaks that are not ours; the C++ suite above keeps detect_leaks=1. Few examples per
# argument (ASan runs about 3x slower): this run looks for memory errors, not for more inputs.
# -O1 -g1: the optimisation level ASan's documentation recommends (and a quicker build than -O2 -g).
ASAN_PY_DIR := build/asan-py
ASAN_EXAMPLES ?= 6
test-asan: deps
	$(VENV)/bin/cmake -S . -B $(ASAN_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DINDOORLOC_SANITIZE=address,undefined -DINDOORLOC_BUILD_PYTHON=OFF >/dev/null
	$(VENV)/bin/cmake --build $(ASAN_DIR)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --test-dir $(ASAN_DIR) -j$(JOBS) --output-on-failure
	$(MAKE) --no-print-directory test-asan-python

test-asan-python: install
	$(VENV)/bin/cmake -S . -B $(ASAN_PY_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
	  -DINDOORLOC_SANITIZE=address,undefined -DINDOORLOC_BUILD_PYTHON=ON -DINDOORLOC_BUILD_TESTS=OFF \
	  -DPython_EXECUTABLE=$(abspath $(PY)) -Dpybind11_DIR=$$($(PY) -m pybind11 --cmakedir) >/dev/null
	$(VENV)/bin/cmake --build $(ASAN_PY_DIR) --target _core
	rm -rf $(ASAN_PY_DIR)/python && mkdir -p $(ASAN_PY_DIR)/python
	cp -r python/indoorloc $(ASAN_PY_DIR)/python/ && rm -f $(ASAN_PY_DIR)/python/indoorloc/_core*.so
	cp $(ASAN_PY_DIR)/bindings/_core*.so $(ASAN_PY_DIR)/python/indoorloc/
	cd tests/python && export PYTHONPATH=$(abspath $(ASAN_PY_DIR)/python) \
	  LD_PRELOAD="$$(gcc -print-file-name=libasan.so) $$(gcc -print-file-name=libstdc++.so)" \
	  PROPERTY_EXAMPLES=$(ASAN_EXAMPLES) \
	  PROPERTY_CALL_TIMEOUT_S=60 PROPERTY_GROUP_TIMEOUT_S=900 \
	  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 && \
	  ../../$(PY) -c "import indoorloc._core as c; assert '$(ASAN_PY_DIR)/python' in c.__file__, c.__file__; \
	    print('property suite against', c.__file__)" && \
	  ../../$(PY) -m pytest -q -c ../../pyproject.toml --rootdir ../.. test_properties_*.py

# Peers (the `bench` extra: particles, which pins numpy < 2) go into their own venv so that the
# test venv keeps the versions CI uses.
BENCH_VENV := .venv-bench
bench: deps-debian
	test -x $(BENCH_VENV)/bin/python || $(PYTHON) -m venv $(BENCH_VENV)
	$(BENCH_VENV)/bin/python -m pip --disable-pip-version-check -q install $(BUILD_REQUIREMENTS)
	$(BENCH_VENV)/bin/python -m pip --disable-pip-version-check -q install --no-build-isolation \
	  -Cbuild-dir=build/bench ".[bench]"
	$(BENCH_VENV)/bin/python benchmarks/run.py

clean:
	rm -rf build reports
