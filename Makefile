# The two commands of the README: `make demo` and `make test`. Each installs the
# missing Debian packages and builds first.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
# Extra CMake arguments, e.g. CMAKE_EXTRA=-DSOFTHD_WITH_MPI=ON (what CI builds); deps then
# installs the MPI packages too (scripts/install-deps.sh --mpi).
CMAKE_EXTRA ?=
DEPS_FLAGS ?= $(if $(findstring SOFTHD_WITH_MPI=ON,$(CMAKE_EXTRA)),--mpi,)

.PHONY: deps build test demo example-scan bench bench-quick tools fuzz docs clean format

deps:
	@scripts/install-deps.sh $(DEPS_FLAGS)

build: deps
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_EXTRA) > $(BUILD_DIR)/configure.log 2>&1 || (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS)

# CTest runs JOBS tests at once, most of them with an OpenMP team of their own: threads
# that wait sleep (OMP_WAIT_POLICY=passive) rather than spin on the cores the other tests
# need. Measured on 2 cores, the suite without the sanitizer run: 140 s against 169-186 s
# spinning (user time 225 s against 288 s).
test: build
	@cd $(BUILD_DIR) && OMP_WAIT_POLICY=passive ctest --output-on-failure -j $(JOBS)

# The demo needs only the library and the softhd tool, not the tests and benchmarks.
demo: deps
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_EXTRA) > $(BUILD_DIR)/configure.log 2>&1 || (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target softhd_cli
	@scripts/demo.sh $(BUILD_DIR)

# The worked example of docs/guide.md ("Worked example: your own scan"): a synthetic depth view
# taken through clean-up, align and a camera-frame optimise; needs the tool and the Python
# module only. Its pictures go to results/scan_example/ (docs/ holds the committed ones).
example-scan: deps
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_EXTRA) > $(BUILD_DIR)/configure.log 2>&1 || (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target softhd_cli softhd_python softhd_python_files
	@PYTHONPATH=$(BUILD_DIR)/python MPLBACKEND=Agg /usr/bin/python3 examples/scan_example.py \
	  --softhd $(BUILD_DIR)/apps/softhd --out results/scan_example $(EXAMPLE_ARGS)

# All benchmarks (within an hour on 2 cores; the run record gives each one's wall time): CSVs and plots in docs/bench/, the report
# docs/benchmarks.md. bench-quick is the smoke variant (about a minute; CTest runs it too).
bench: build
	@scripts/run_benchmarks.sh $(BUILD_DIR) docs/bench docs/benchmarks.md

bench-quick: build
	@scripts/run_benchmarks.sh --quick $(BUILD_DIR) $(BUILD_DIR)/bench-quick $(BUILD_DIR)/bench-quick/benchmarks.md

# The measurement tools the docs cite (tools/: bench_state, bench_cloud_pair, bench_pass_sample,
# and bench_mpi_sums in an MPI build) into $(BUILD_DIR)/tools/.
tools: build
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target tools

# libFuzzer targets (clang, ASan+UBSan) in their own tree, each run for FUZZ_SECONDS.
FUZZ_DIR ?= build-fuzz
FUZZ_SECONDS ?= 600
fuzz: deps
	@mkdir -p $(FUZZ_DIR)
	@cmake -S . -B $(FUZZ_DIR) -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None \
	  "-DCMAKE_CXX_FLAGS=-O1 -g1 -Wno-pass-failed" -DSOFTHD_SANITIZE=ON -DSOFTHD_FUZZ=ON \
	  -DSOFTHD_BUILD_TESTS=OFF -DSOFTHD_BUILD_APPS=OFF -DSOFTHD_BUILD_BENCH=OFF \
	  > $(FUZZ_DIR)/configure.log 2>&1 || (cat $(FUZZ_DIR)/configure.log; exit 1)
	@cmake --build $(FUZZ_DIR) -j $(JOBS) --target fuzz_text_cloud fuzz_ply_cloud fuzz_pcd_cloud fuzz_scene fuzz_checkpoint fuzz_msh
	@scripts/fuzz.sh $(FUZZ_DIR) $(FUZZ_SECONDS)

# The API reference of the public headers (Doxygen): $(BUILD_DIR)/docs/html/index.html.
docs: deps
	@scripts/docs.sh $(BUILD_DIR)/docs

format:
	@git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

clean:
	@rm -rf $(BUILD_DIR)
