# Entry points; see README.md. Every target that builds first installs missing Debian packages
# (scripts/install-deps.sh, a quick no-op when everything is there).
BUILD ?= build
ASAN_BUILD ?= build-asan
JOBS ?= $(shell nproc)
PYTHON ?= /usr/bin/python3
CMAKE_FLAGS ?=

.PHONY: all deps build test-programs test test-slow test-sanitize reproduce experiment bench bench-short bench-record dashboard viewer test-browser clean

all: build

deps:
	@bash scripts/install-deps.sh

CONFIGURE = cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) > /dev/null

build: deps
	@$(CONFIGURE)
	@cmake --build $(BUILD) -j $(JOBS)

# What the tests run (the target cdp_test_programs: no benchmarks).
test-programs: deps
	@$(CONFIGURE)
	@cmake --build $(BUILD) -j $(JOBS) --target cdp_test_programs

# Every test but the slow tier (ctest label slow, tests/CMakeLists.txt: CDP_SLOW), which
# make test-slow runs; CI runs both.
test: test-programs
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -LE '^slow$$'

test-slow: test-programs
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -L '^slow$$'

# The same tests under AddressSanitizer and UndefinedBehaviorSanitizer (CI runs this too), but
# for those labelled slow_under_sanitizers or slow (tests/CMakeLists.txt).
# -O1 -g1 (line tables, enough for the sanitizers' stack traces): the instrumented build was
# the longest step of CI (23 of its 46 minutes at -O2 -g); these halve the compile time of a
# heavy file (quality.cpp 45 -> 24 s, adaptive/polygonizer_test.cpp 36 -> 20 s).
test-sanitize: deps
	@cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
	    -DCDP_SANITIZE=ON -DCDP_BUILD_BENCHMARKS=OFF > /dev/null
	@cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j $(JOBS) \
	    -LE '^(slow_under_sanitizers|slow)$$'

reproduce: build
	$(PYTHON) scripts/reproduce.py --build $(BUILD) --jobs $(JOBS)

# make experiment EXP=experiments/NAME.json
experiment: build
	$(BUILD)/bin/experiment $(EXP)

bench: build
	$(PYTHON) scripts/run_benchmarks.py --build $(BUILD) --out results/bench/latest.json

bench-short: build
	$(PYTHON) scripts/run_benchmarks.py --build $(BUILD) --short --out results/bench/latest.json

bench-record: bench
	$(PYTHON) scripts/record_benchmark.py results/bench/latest.json results/bench/history

dashboard:
	$(PYTHON) scripts/make_dashboard.py --history results/bench/history --latest results/bench/latest.json \
	    --table results/table1.json --out results/dashboard/index.html

# The mesh viewer, results/viewer/ (make reproduce makes it too). In a fresh clone, where the meshes of
# make reproduce are missing, its meshes are made again by the experiment program: built first then.
viewer:
	@bash scripts/install-deps.sh --viewer
	@$(PYTHON) scripts/make_viewer.py --build $(BUILD) --have-meshes || $(MAKE) build
	$(PYTHON) scripts/make_viewer.py --build $(BUILD)

test-browser: dashboard viewer
	@bash scripts/install-deps.sh --browser
	$(PYTHON) scripts/test_dashboard_browser.py results/dashboard/index.html
	node viewer/test/browser.mjs results/viewer/index.html --screenshots results/viewer/screenshots

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
