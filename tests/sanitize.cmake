# The whole suite under AddressSanitizer + UBSan, and the libFuzzer targets' smoke run:
# one clang build (Debian clang; libFuzzer ships with it) in its own tree, every CTest test
# of it run there (the CLI and its tests included), then each fuzz target for FUZZ_SECONDS.
# Variables: SOURCE_DIR, WORK_DIR, FUZZ_SECONDS.
find_program(CLANGXX clang++)
if(NOT CLANGXX)
  message(FATAL_ERROR "the sanitizer suite needs clang++ (apt-get install clang libclang-rt-14-dev, "
                      "or run scripts/install-deps.sh)")
endif()
# -O1 -g1 (line tables for the reports): the build is most of this test's time. To make it
# cheaper, with every file still compiled and run under ASan+UBSan: one precompiled header
# for the library and one for the test executables (Eigen, GoogleTest, the standard
# headers: about 1-4 s of a file's 3-24 s of CPU), and the test executables' own files
# without libFuzzer's coverage instrumentation (the library and the fuzz targets keep it;
# the tests never run under libFuzzer; it also costs them run time: test_hausdorff_dual took
# 101 s of CPU with it, 77 s without). CPU (user+sys) of the build, `/usr/bin/time -v
# cmake --build <tree> -j 2` on a fresh tree configured as here (Dec 2, shared machine):
# 1032 s before, 765 s with these three; the test run below (ctest -j 2, user+sys) 434 s
# before, 409 s after (all 553 passing both times).
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}
  -DCMAKE_CXX_COMPILER=${CLANGXX} -DCMAKE_BUILD_TYPE=None
  "-DCMAKE_CXX_FLAGS=-O1 -g1 -Wno-pass-failed" -DSOFTHD_SANITIZE=ON -DSOFTHD_FUZZ=ON
  -DSOFTHD_BUILD_BENCH=OFF -DSOFTHD_SANITIZER_SUITE=OFF
  -DSOFTHD_LIB_PCH=ON -DSOFTHD_TEST_PCH=ON
  -DSOFTHD_TEST_COMPILE_OPTIONS=-fno-sanitize=fuzzer-no-link
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "configuring the sanitizer build failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR} -j 2 RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "the sanitizer build failed")
endif()
# Left out here (each runs in the main suite): the install test, a packaging check rather
# than a sanitizer one, and tests that repeat code smaller tests run under ASan too, on
# larger problems, where ASan makes the FE code about 20x slower. Their times under ASan on
# an idle machine: the two plate refinement tests 157 s together (the other FE tests'
# assembly and Newton on 10-40 times their meshes); OptimiseCli.KilledAndResumed... 72 s
# (ten trials of killed CLI runs; resuming is also in ResumeIsTheSameRun.* and
# OptimiseCli.IterationLimitIsATotalOverResumes); Newton.OptionsChangeThePath... 40 s (16
# Newton solves); ShapeObjective.TwoLevelStarts... 39 s (grid sequencing, as in
# GridSequencing.*); Newton.ZeroControlConvergesAtRest 25 s (the torsion scene's set-up).
# With the last four, this run's tests took 375 s at -j 2 (Dec 1).
set(heavy "install_and_consume|Plate\\.HardCaseIsReachedFromFlat"
  "Plate\\.TipDisplacementConvergesUnderQ2Refinement"
  "OptimiseCli\\.KilledAndResumedRunsAreTheUninterruptedRun"
  "OptimiseCli\\.MultilevelKilledAndResumedRunsAreTheUninterruptedRun"
  "Newton\\.OptionsChangeThePathNotTheEquilibrium|Newton\\.ZeroControlConvergesAtRest"
  "ShapeObjective\\.TwoLevelStartsReachTheSameStateWithFewerFineIterations"
  # 17 s in the main suite (six Newton solves up to 15 000 P2 dofs), 20x that under ASan;
  # the same P2 tetrahedra run under ASan in GmshMesh.* and Lumping.*.
  "Convergence\\.P2TetrahedraConvergeFasterThanP1AtTheirOrders"
  # 1.6 s in the main suite (two tracking runs of 15 iterations), about 20x that under ASan;
  # the same objective (visible mask, boundary cloud, adjoint) runs under ASan in
  # Particles/VisibleGradient.*.
  "VisibleObjective\\.TracksAHalfViewBetterThanTheSymmetricDistance"
  # clang's libomp leaks its team bookkeeping (2.9 KB, LeakSanitizer) when asked for 100000
  # threads; the test checks softhd's clamp and runs in the main suite (libgomp).
  "Threads\\.AnOpenMpDefaultAboveTheCapIsClampedNotCrashed"
  # 16 alignments together (about 1 s of CPU each in the main suite); the same code runs
  # under ASan in Align.MovedScanGivesComposedPose (two alignments) and the Taylor test.
  "Align\\.ExactSubsetRecoveredFromTenRandomRotations|Align\\.SimilarityRecovered"
  "Align\\.DistanceMinimiserAloneIsCloseButBiased"
  # about 2.5 s of CPU in the main suite (five CLI runs, one of 12 joint pose-and-control
  # iterations); the joint objective and run run under ASan in Pose/JointGradient.* and
  # ResumeIsTheSameRun.WithAJointPose.
  "OptimiseCli\\.CameraFrameTargetRefinesThePoseWithTheControl")
list(JOIN heavy "|" heavy)
execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir ${WORK_DIR} -j 2 --output-on-failure
  -E "^(${heavy})$"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc)
  message(FATAL_ERROR "tests failed under ASan+UBSan:\n${out}\n${err}")
endif()
string(REGEX MATCH "[0-9]+% tests passed[^\n]*" passed "${out}")
message(STATUS "ASan+UBSan: ${passed}")
# Two fuzz targets at a time (one core each), each for FUZZ_SECONDS.
execute_process(COMMAND ${SOURCE_DIR}/scripts/fuzz.sh ${WORK_DIR} ${FUZZ_SECONDS} 2
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(rc)
  message(FATAL_ERROR "a fuzz target found a problem:\n${out}\n${err}")
endif()
