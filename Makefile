# Embody: the two commands a new user needs are `make demo` and `make test`.
# Every target installs what is missing (scripts/install-deps.sh) and builds first.
BUILD      ?= build
BUILD_TYPE ?= Release
JOBS       ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_ARGS ?=
CTEST_ARGS ?=
WERROR     := $(if $(CI),-DEMBODY_WERROR=ON,)

space := $(empty) $(empty)

.PHONY: all deps build demo test bench sanitize tsan fuzz soak format clean

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(WERROR) $(CMAKE_ARGS)

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	@bash scripts/demo.sh $(BUILD)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) $(CTEST_ARGS)

bench: build
	cmake --build $(BUILD) -j $(JOBS) --target embody_benchmarks
	@bash scripts/bench.sh $(BUILD)

# ASan + UBSan build of the whole suite; Mesa/LLVM leaks are suppressed (scripts/lsan.supp).
sanitize: deps
	cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DEMBODY_SANITIZE=ON -DEMBODY_BUILD_BENCH=OFF $(WERROR)
	cmake --build build-sanitize -j $(JOBS)
	# Leak checking on the CPU-only tests. Everything that starts lavapipe (gpu, window, xr, and
	# the cli tests, which run the renderer) runs with detect_leaks=0: lavapipe's JIT-compiled
	# shader code allocates from frames LSan sees as <unknown module>, which no suppression can name.
	cd build-sanitize && \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan.supp:print_suppressions=0 \
	  ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) -L unit -E '^cli:' $(CTEST_ARGS)
	cd build-sanitize && \
	  ASAN_OPTIONS=detect_leaks=0:abort_on_error=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) -LE unit $(CTEST_ARGS)
	cd build-sanitize && \
	  ASAN_OPTIONS=detect_leaks=0:abort_on_error=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) -R '^cli:' $(CTEST_ARGS)

# ThreadSanitizer on the tests of the code that has threads: the runtime (IK thread, triple
# buffers, IkStage), tracking, and xr (the XR frame loop with its IK thread and late latch, the
# headless runtime's blocking xrWaitFrame, SIGINT handling; the CLI and the runtime library are
# built with TSan too). Only those targets are built. Mesa and the validation layer are not
# instrumented: scripts/tsan.supp silences them. TSAN_TESTS picks other suites.
TSAN_TESTS ?= runtime tracking xr
tsan: deps
	cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DEMBODY_TSAN=ON -DEMBODY_BUILD_BENCH=OFF $(WERROR)
	cmake --build build-tsan -j $(JOBS) --target $(addprefix embody_tests_,$(TSAN_TESTS)) embody embody_xr_runtime
	cd build-tsan && TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$(CURDIR)/scripts/tsan.supp \
	  ctest --output-on-failure -j $(JOBS) -R '^($(subst $(space),|,$(strip $(TSAN_TESTS)))):' $(CTEST_ARGS)

# libFuzzer (clang, build-fuzz/) on every parser of outside data, FUZZ_SECONDS per target, from the
# kept corpus in fuzz/corpus; results in out/fuzz/summary.md (docs/reliability.md). CI's smoke is
# the gcc replay in `make test` (ctest -R '^fuzz:').
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= gltf vrm bone_map bvh trace spine profile xr_poses
fuzz:
	@bash scripts/install-deps.sh --fuzz
	CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DEMBODY_FUZZ=ON \
	  -DEMBODY_BUILD_TESTS=OFF -DEMBODY_BUILD_BENCH=OFF $(WERROR)
	cmake --build build-fuzz -j $(JOBS) --target $(addprefix embody_fuzz_,$(FUZZ_TARGETS))
	@bash scripts/fuzz.sh build-fuzz $(FUZZ_SECONDS) $(FUZZ_TARGETS)

# The soak: the runtime under injected faults for SOAK_SECONDS (docs/reliability.md).
SOAK_SECONDS ?= 1800
soak: build
	mkdir -p out && $(BUILD)/bench/embody_soak --seconds $(SOAK_SECONDS) --json out/soak.json

format:
	git ls-files '*.cpp' '*.h' '*.vert' '*.frag' '*.comp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) build-sanitize build-tsan build-fuzz out
