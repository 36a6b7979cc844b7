# The whole suite under AddressSanitizer + UBSan, and the libFuzzer targets' smoke run:
# one clang build (Debian clang; libFuzzer ships with it) in its own tree, every CTest test
# of it run there (the CLI and its tests included), then each fuzz target for FUZZ_SECONDS.
# Variables: SOURCE_DIR, WORK_DIR, FUZZ_SECONDS.
find_program(CLANGXX clang++)
if(NOT CLANGXX)
  message(FATAL_ERROR "the sanitizer suite needs clang++ (apt-get install clang libclang-rt-14-dev, "
                      "or run scripts/install-deps.sh)")
endif()
# -O1 -g1 (line tables for the reports): the build is most of this test's time.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}
  -DCMAKE_CXX_COMPILER=${CLANGXX} -DCMAKE_BUILD_TYPE=None
  "-DCMAKE_CXX_FLAGS=-O1 -g1 -Wno-pass-failed" -DSOFTHD_SANITIZE=ON -DSOFTHD_FUZZ=ON
  -DSOFTHD_BUILD_BENCH=OFF -DSOFTHD_SANITIZER_SUITE=OFF
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "configuring the sanitizer build failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR} -j 2 RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "the sanitizer build failed")
endif()
# The install test builds a consumer against the install tree: a packaging check, not a
# sanitizer one (it runs in the main suite). The two plate refinement tests run the
# assembly and Newton code of the other FE tests on 10-40 times their meshes: under ASan
# they took 157 s of the 528 s of this run's tests (they run in the main suite).
execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir ${WORK_DIR} -j 2 --output-on-failure
  -E "^(install_and_consume|Plate\\.HardCaseIsReachedFromFlat|Plate\\.TipDisplacementConvergesUnderQ2Refinement)$"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc)
  message(FATAL_ERROR "tests failed under ASan+UBSan:\n${out}\n${err}")
endif()
string(REGEX MATCH "[0-9]+% tests passed[^\n]*" passed "${out}")
message(STATUS "ASan+UBSan: ${passed}")
execute_process(COMMAND ${SOURCE_DIR}/scripts/fuzz.sh ${WORK_DIR} ${FUZZ_SECONDS}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(rc)
  message(FATAL_ERROR "a fuzz target found a problem:\n${out}\n${err}")
endif()
