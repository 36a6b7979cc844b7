# The suite under AddressSanitizer + UBSan, and the libFuzzer targets' smoke run: one clang
# build (Debian clang; libFuzzer ships with it) in its own tree, WORK_DIR. CTest runs this
# script as several tests (tests/CMakeLists.txt), one STEP each:
#   configure        configure the tree and build what the other steps share (the library,
#                    the CLI, the test executables' precompiled header); the fixture's setup
#   test EXE=name    build the test executable `name` and run its GoogleTest tests there
#   scripts          the tree's tests that are not GoogleTest executables (the CLI's scripts,
#                    the documentation checks); after every `test` step
#   fuzz TARGET=t    build the libFuzzer target fuzz_t and run it for FUZZ_SECONDS
# Variables: STEP, SOURCE_DIR, WORK_DIR, EXE, TARGET, FUZZ_SECONDS.
#
# Two builds in one tree at once are safe when they share no out-of-date target: the
# configure step builds everything shared, twice (the second, a no-op, also writes the
# library's consolidated dependency files, which the other steps' builds then only read).
# Each test step reads only its own executable's test list, written by its own build.
# The tests run are the tree's tests less those listed below. `ctest -j 2 -R '^sanitizer\.'`
# (Dec 6, on 2 cores loaded by other builds, load average 6-12): 2225 s wall, 1370 s of CPU
# (user+sys), with part of the library built before it started.

# Left out here (each runs in the main suite): the install test, a packaging check rather
# than a sanitizer one, and tests that repeat code smaller tests run under ASan too, on
# larger problems, where ASan makes the FE code about 20x slower. Their times under ASan on
# an idle machine: the two plate refinement tests 157 s together (the other FE tests'
# assembly and Newton on 10-40 times their meshes); OptimiseCli.KilledAndResumed... 72 s
# (ten trials of killed CLI runs; resuming is also in ResumeIsTheSameRun.* and
# OptimiseCli.IterationLimitIsATotalOverResumes); Newton.OptionsChangeThePath... 40 s (16
# Newton solves); ShapeObjective.TwoLevelStarts... 39 s (grid sequencing, as in
# GridSequencing.*); Newton.ZeroControlConvergesAtRest 25 s (the torsion scene's set-up).
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
  "OptimiseCli\\.CameraFrameTargetRefinesThePoseWithTheControl"
  # flag tests of the main suite, 6-14 s each there (seven forward solves; three optimise
  # runs of 8 iterations, two of them on two levels): they show each flag's effect; the
  # Newton, the levels and the cloud target they drive run under ASan in Newton.*,
  # Multilevel.* and OptimiseCli's shorter runs.
  "Cli\\.ForwardSolverFlagsChangeTheNewtonRunAsDocumented"
  "OptimiseCli\\.TargetFlagIsTheScenesCloudTargetOfThatFile"
  "OptimiseCli\\.CoarseIterationsAndRefinedMoveLimitActOnTheirLevels"
  # 21 s under ASan (Dec 7; the cell distance's gradient on 3³ cells against a shifted copy,
  # the smallest size at which a wrong rule for lines lying in the surface shows): the same
  # gradient code runs under ASan in CellDistance.GradientTaylorOfRho and ...OfOneCell.
  "CellDistance\\.GradientOfCoincidentFaces")
list(JOIN heavy "|" heavy)

# cmake --build WORK_DIR -j JOBS --target TARGETS...; a failure prints the build's output.
function(sanitizer_build jobs)
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR} -j ${jobs} --target ${ARGN}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(rc)
    message(FATAL_ERROR "the sanitizer build of ${ARGN} failed:\n${out}")
  endif()
endfunction()

# ctest in DIR, the heavy tests left out (an executable may have none left: it is still
# built under the sanitizers).
function(sanitizer_ctest dir)
  execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir ${dir} --output-on-failure
    --no-tests=ignore -E "^(${heavy})$" ${ARGN}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "tests failed under ASan+UBSan:\n${out}\n${err}")
  endif()
  string(REGEX MATCH "[0-9]+% tests passed[^\n]*" passed "${out}")
  if(NOT passed)
    set(passed "no test left to run (all in the heavy list)")
  endif()
  message(STATUS "ASan+UBSan: ${passed}")
endfunction()

if(STEP STREQUAL "configure")
  find_program(CLANGXX clang++)
  if(NOT CLANGXX)
    message(FATAL_ERROR "the sanitizer suite needs clang++ (apt-get install clang "
                        "libclang-rt-14-dev, or run scripts/install-deps.sh)")
  endif()
  # ccache, when installed, makes a rebuilt tree (CI's reruns, the same path again) cheap.
  # A file compiled against a precompiled header is one ccache refuses ("could not use
  # precompiled header": every library and test file here) unless the header is hashed
  # (sloppiness pch_defines, time_macros; the mtime checks off, the header being new) and
  # clang leaves its inputs' timestamps out of it (-fno-pch-timestamp).
  find_program(CCACHE ccache)
  set(launcher "-DCMAKE_CXX_COMPILER_LAUNCHER=")  # one argument, quoted: it is a list
  set(pch_flags)
  if(CCACHE)
    set(sloppiness pch_defines,time_macros,include_file_mtime,include_file_ctime)
    set(launcher "${launcher}${CMAKE_COMMAND};-E;env;CCACHE_SLOPPINESS=${sloppiness};${CCACHE}")
    set(pch_flags " -Xclang -fno-pch-timestamp")
  endif()
  # -O1 -g1 (line tables for the reports): the build is most of the suite's time. To make
  # it cheaper, with every file still compiled and run under ASan+UBSan: one precompiled
  # header for the library and one for the test executables (Eigen, GoogleTest, the
  # standard headers: about 1-4 s of a file's 3-24 s of CPU), and the test executables'
  # own files without libFuzzer's coverage instrumentation (the library and the fuzz
  # targets keep it; the tests never run under libFuzzer; it also costs them run time:
  # test_hausdorff_dual took 101 s of CPU with it, 77 s without). CPU (user+sys) of the
  # whole build, `/usr/bin/time -v cmake --build <tree> -j 2` on a fresh tree configured as
  # here (Dec 2, shared machine): 1032 s before, 765 s with these three.
  # The library parts whose work no fuzz target's parser does (the distance and its
  # kernels, the scans; of them the parsers call only PointCloud's checks and enum-name
  # parsers) without libFuzzer's coverage either: it made the pair kernel 3.4x slower
  # under ASan. Interrupt.TheCheckIsPolledBetweenBlocksOfAPassAndStopsTheDistance (Dec 7,
  # the fresh clone's objects, pair_kernel.cpp and pair_backend.cpp rebuilt without it):
  # 44.9 s of CPU with the coverage, 13.3 s without. io keeps it; of fe and control, the
  # files no parser reaches (the FE solver, the objective's evaluation, the optimisers and
  # the run: tests/sanitize_uncovered.txt) are left without it by clang's ignore list, the
  # scene, target, pose and checkpoint parsers and the body they build keep it. Compiling
  # fe/assembly.cpp (Dec 7, the same command, `/usr/bin/time`): 31.7 s of CPU with the
  # coverage, 25.7 s without.
  # lld, when installed (Debian lld), links the tree's ~60 executables against the
  # instrumented static library: measured on test_cli and test_hausdorff_dual's links
  # (Dec 7, `/usr/bin/time`, the same objects), 1.3 and 0.9 s of CPU with GNU ld against
  # 0.6 and 0.5 s with lld, and half the wall time.
  find_program(LLD ld.lld)
  set(linker)
  if(LLD)
    set(linker -DCMAKE_EXE_LINKER_FLAGS=-fuse-ld=lld)
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}
    -DCMAKE_CXX_COMPILER=${CLANGXX} -DCMAKE_BUILD_TYPE=None "${launcher}" ${linker}
    "-DCMAKE_CXX_FLAGS=-O1 -g1 -Wno-pass-failed${pch_flags}" -DSOFTHD_SANITIZE=ON -DSOFTHD_FUZZ=ON
    -DSOFTHD_BUILD_BENCH=OFF -DSOFTHD_SANITIZER_SUITE=OFF
    -DSOFTHD_LIB_PCH=ON -DSOFTHD_TEST_PCH=ON
    -DSOFTHD_TEST_COMPILE_OPTIONS=-fno-sanitize=fuzzer-no-link
    "-DSOFTHD_FUZZ_UNCOVERED=hausdorff;scan"
    -DSOFTHD_FUZZ_IGNORELIST=${SOURCE_DIR}/tests/sanitize_uncovered.txt
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(rc)
    message(FATAL_ERROR "configuring the sanitizer build failed:\n${out}")
  endif()
  # The CLI pulls in the library; test_point_cloud owns the tests' precompiled header.
  sanitizer_build(2 softhd_cli test_point_cloud)
  sanitizer_build(1 softhd_cli test_point_cloud)
elseif(STEP STREQUAL "test")
  sanitizer_build(1 ${EXE})
  # A directory whose test list is this executable's alone (CTest reads no other
  # executable's list, which another step's build may be writing).
  set(dir ${WORK_DIR}/sanitizer-ctest/${EXE})
  set(include "${WORK_DIR}/tests/${EXE}[1]_include.cmake")  # gtest_discover_tests' name
  if(NOT EXISTS "${include}")
    message(FATAL_ERROR "no test list of ${EXE}: ${include}")
  endif()
  file(WRITE ${dir}/CTestTestfile.cmake "include(\"${include}\")\n")
  sanitizer_ctest(${dir})
elseif(STEP STREQUAL "scripts")
  # The tests without a label: every GoogleTest test has its executable's name as label.
  sanitizer_ctest(${WORK_DIR} -LE .)
elseif(STEP STREQUAL "fuzz")
  sanitizer_build(1 fuzz_${TARGET})
  execute_process(COMMAND ${SOURCE_DIR}/scripts/fuzz.sh ${WORK_DIR} ${FUZZ_SECONDS} 1 ${TARGET}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}")
  if(rc)
    message(FATAL_ERROR "a fuzz target found a problem:\n${out}\n${err}")
  endif()
else()
  message(FATAL_ERROR "sanitize.cmake: unknown STEP '${STEP}'")
endif()
