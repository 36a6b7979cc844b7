# Builds the unit tests with AddressSanitizer + UBSan in a separate tree and runs them.
# Variables: SOURCE_DIR, WORK_DIR, TESTS (comma-separated test executables).
string(REPLACE "," ";" TESTS "${TESTS}")
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTHD_SANITIZE=ON -DSOFTHD_BUILD_BENCH=OFF
  -DSOFTHD_BUILD_APPS=OFF -DSOFTHD_SANITIZER_SUITE=OFF
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "configuring the sanitizer build failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR} -j 2 --target ${TESTS}
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "the sanitizer build failed")
endif()
foreach(t ${TESTS})
  execute_process(COMMAND ${WORK_DIR}/tests/${t} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "${t} failed under ASan+UBSan:\n${out}\n${err}")
  endif()
  message(STATUS "${t}: passed under ASan+UBSan")
endforeach()
