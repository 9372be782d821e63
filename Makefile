# candi: the two commands are `make demo` and `make test`; both set up a bare Debian 12 machine
# (packages via scripts/deps.sh), configure, build, then run the main job / the tests.
BUILD_DIR ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=
CTEST_FLAGS ?= --output-on-failure
# Tests labelled "slow", and those guarded by CANDI_REQUIRE_SLOW_TESTS (long real-data runs), are
# left to `make test-all`.
CTEST_EXCLUDE ?= -LE slow

.PHONY: all deps deps-fuzz configure build test test-all test-stress test-asan test-tsan demo bench fuzz clean format

all: build

deps:
	@bash scripts/deps.sh

# clang and its runtimes, only for `make fuzz`.
deps-fuzz:
	@bash scripts/deps.sh fuzz

$(BUILD_DIR)/build.ninja: | deps
	@cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release -DCANDI_WERROR=ON $(CMAKE_FLAGS)

configure: $(BUILD_DIR)/build.ninja

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest $(CTEST_FLAGS) -j $(JOBS) $(CTEST_EXCLUDE)

test-all: build
	@cd $(BUILD_DIR) && CANDI_SLOW_TESTS=1 ctest $(CTEST_FLAGS) -j $(JOBS)

# The suite of `make test` STRESS_RUNS times (5) with two busy loops competing for the cores;
# lists every test that failed even once (scripts/stress.sh; STRESS_TESTS=regex for some).
STRESS_RUNS ?= 5
test-stress: build
	@STRESS_RUNS=$(STRESS_RUNS) STRESS_JOBS=$(JOBS) CTEST_EXCLUDE="$(CTEST_EXCLUDE)" bash scripts/stress.sh $(BUILD_DIR)

# The whole suite built with AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/, GCC,
# -O1 -g): every report fails its test. Slow: not part of `make test`.
test-asan: deps
	@bash scripts/sanitize.sh asan

# ThreadSanitizer on the multi-threaded parts: the renderer (SPBR, streaming, archive) and the
# dense stereo (PatchMatch, fusion), run with 2 threads (build-tsan/).
test-tsan: deps
	@bash scripts/sanitize.sh tsan

demo: build
	@$(BUILD_DIR)/apps/candi demo -o demo_out

bench: build
	@bash scripts/bench.sh $(BUILD_DIR)

# libFuzzer targets of fuzz/ (clang, ASan + UBSan) in build-fuzz/, each run FUZZ_SECONDS (60) on
# its corpus; `make test` only replays their seeds and regressions (GCC build, ctest label fuzz).
FUZZ_SECONDS ?= 60
fuzz: deps deps-fuzz
	@FUZZ_SECONDS=$(FUZZ_SECONDS) bash scripts/fuzz.sh

format:
	@git ls-files '*.h' '*.cc' | xargs clang-format -i

clean:
	@rm -rf $(BUILD_DIR) build-fuzz build-asan build-tsan demo_out
