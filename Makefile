# viewpose: the commands the README names. Each target installs the Debian packages it needs
# (scripts/install-deps.sh, apt-get; sudo when not root), configures, builds and runs.
#   make demo           build, then run the main job on data the program makes itself
#   make test           build and run the whole test suite (ctest)
#   make test-sanitize  the same suite under AddressSanitizer + UndefinedBehaviorSanitizer
#   make test-thread    the same suite under ThreadSanitizer (clang, libomp with its Archer tool)
#   make fuzz           build the libFuzzer targets (clang) and run each for FUZZ_SECONDS
#   make check          all four, as CI runs them
#   make bench          micro-benchmarks of each stage, the pipeline over 100 simulated frames, then the
#                       real frames of ../shared/data (scripts/bench-real.py; docs/results/bench_real.json)
#   make bench-pcl      install PCL, and time the thesis's PCL pipeline beside ours, stage by stage
#   make bench-opencv   install OpenCV's surface_matching, and set our point pair votes beside its PPF3DDetector
#   make results        real frames, simulated rooms, the thesis's experiment; writes docs/RESULTS.md
#   make confidence     make the simulated data the confidence model is fit on, and fit it (docs/CONFIDENCE.md)
#   make pcl-fixtures   install PCL, and regenerate tests/fixtures/pcl from PCL's own code
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
FUZZ_SECONDS ?= 60
PCL_FRAMES ?= 12
BUILD := build
# The sanitizer and fuzzer builds: clang at -O1 with line tables compiles 4x faster than GCC at
# -O2 -g under ASan (41 s -> 11 s for recognizer.cpp) and still names file and line in every report.
SANITIZER_BUILD = -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only"
# LLVM's OpenMP tool that tells ThreadSanitizer about libomp's barriers and locks (libomp-dev).
ARCHER = $(firstword $(wildcard /usr/lib/llvm-*/lib/libarcher.so))
CMAKE_FLAGS ?=
# The first lines a user sees are the build's and the demo's, not make's "Entering directory" (passed on to
# the makefiles CMake generates, which cmake --build runs).
MAKEFLAGS += --no-print-directory

.PHONY: all deps build demo test test-sanitize test-thread fuzz check bench bench-pcl bench-opencv results confidence pcl-fixtures clean

all: build

deps:
	@scripts/install-deps.sh build

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

# The demo needs the command alone: its build is shorter, and says less before the demo speaks.
demo: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS) --target viewpose_cli
	@./$(BUILD)/viewpose demo --out demo-out

test: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-sanitize:
	@scripts/install-deps.sh build fuzz
	@CXX=clang++ cmake -S . -B build-sanitize $(SANITIZER_BUILD) -DVIEWPOSE_SANITIZE=ON -DVIEWPOSE_BENCH=OFF >/dev/null
	@cmake --build build-sanitize -j $(JOBS)
	@cd build-sanitize && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j $(JOBS)

# Reports from code that is not instrumented (libomp, the camera drivers) are ignored: see tests/tsan.supp.
test-thread:
	@scripts/install-deps.sh build fuzz
	@test -n "$(ARCHER)" || { echo "test-thread: libarcher.so (libomp-dev) not found"; exit 1; }
	@CXX=clang++ cmake -S . -B build-thread $(SANITIZER_BUILD) -DVIEWPOSE_THREAD_SANITIZE=ON -DVIEWPOSE_BENCH=OFF >/dev/null
	@cmake --build build-thread -j $(JOBS)
	@cd build-thread && OMP_TOOL_LIBRARIES=$(ARCHER) \
	  TSAN_OPTIONS="suppressions=$(CURDIR)/tests/tsan.supp ignore_noninstrumented_modules=1 halt_on_error=1 second_deadlock_stack=1" \
	  ctest --output-on-failure -j $(JOBS)

fuzz:
	@scripts/install-deps.sh build fuzz
	@CXX=clang++ cmake -S . -B build-fuzz $(SANITIZER_BUILD) -DVIEWPOSE_FUZZ=ON >/dev/null
	@cmake --build build-fuzz -j $(JOBS)
	@scripts/run-fuzzers.sh build-fuzz $(FUZZ_SECONDS)

check: test test-sanitize test-thread fuzz

bench: build
	@./$(BUILD)/viewpose_bench
	@./$(BUILD)/viewpose bench --frames 100
	@/usr/bin/python3 scripts/bench-real.py --viewpose $(BUILD)/viewpose

bench-pcl: deps
	@scripts/install-deps.sh pcl
	@cmake -S . -B build-pcl-bench -DCMAKE_BUILD_TYPE=Release -DVIEWPOSE_PCL_BENCH=ON -DVIEWPOSE_TESTS=OFF -DVIEWPOSE_BENCH=OFF >/dev/null
	@cmake --build build-pcl-bench -j $(JOBS) --target viewpose_pcl_bench viewpose_cli
	@./build-pcl-bench/viewpose_pcl_bench --frames $(PCL_FRAMES) --json docs/results/pcl_side_by_side.json
	@scripts/bench-pcl-real.sh build-pcl-bench docs/results/pcl_side_by_side.json

bench-opencv: deps
	@scripts/install-deps.sh opencv
	@cmake -S . -B build-opencv-bench -DCMAKE_BUILD_TYPE=Release -DVIEWPOSE_OPENCV_BENCH=ON -DVIEWPOSE_TESTS=OFF -DVIEWPOSE_BENCH=OFF >/dev/null
	@cmake --build build-opencv-bench -j $(JOBS) --target viewpose_opencv_ppf_bench
	@./build-opencv-bench/viewpose_opencv_ppf_bench --json docs/results/opencv_ppf.json

# The thesis's experiment and the real-data check, end to end: writes docs/RESULTS.md and its plots.
results: build
	@scripts/install-deps.sh results
	@/usr/bin/python3 scripts/make-results.py

confidence: build
	@scripts/install-deps.sh results
	@scripts/confidence-data.sh

pcl-fixtures: build
	@scripts/install-deps.sh pcl
	@cmake -S tools/pcl_reference -B build-pcl -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build build-pcl -j $(JOBS)
	@mkdir -p tests/fixtures/pcl
	@./$(BUILD)/tests/make_pcl_input tests/fixtures/jug_view.pcd
	@./build-pcl/pcl_reference tests/fixtures/jug_view.pcd tests/fixtures/pcl

clean:
	rm -rf build build-sanitize build-thread build-fuzz build-pcl build-pcl-bench demo-out
