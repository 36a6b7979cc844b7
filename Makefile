# The two commands of the README: `make demo` and `make test`. Each installs the
# missing Debian packages and builds first.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)

.PHONY: deps build test demo bench bench-quick docs clean format

deps:
	@scripts/install-deps.sh

build: deps
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release > $(BUILD_DIR)/configure.log 2>&1 || (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# The demo needs only the library and the softhd tool, not the tests and benchmarks.
demo: deps
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release > $(BUILD_DIR)/configure.log 2>&1 || (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target softhd_cli
	@scripts/demo.sh $(BUILD_DIR)

# All benchmarks (about 1.5-2 hours on 2 cores): CSVs and plots in docs/bench/, the report
# docs/benchmarks.md. bench-quick is the smoke variant (about a minute; CTest runs it too).
bench: build
	@scripts/run_benchmarks.sh $(BUILD_DIR) docs/bench docs/benchmarks.md

bench-quick: build
	@scripts/run_benchmarks.sh --quick $(BUILD_DIR) $(BUILD_DIR)/bench-quick $(BUILD_DIR)/bench-quick/benchmarks.md

# The API reference of the public headers (Doxygen): $(BUILD_DIR)/docs/html/index.html.
docs: deps
	@scripts/docs.sh $(BUILD_DIR)/docs

format:
	@git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

clean:
	@rm -rf $(BUILD_DIR)
