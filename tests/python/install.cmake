# Installs the build tree into a scratch prefix and imports softhd from there with the
# interpreter the module was built for; checks that the same relative directory under the
# default prefix /usr/local is on that interpreter's own sys.path (so that a plain
# `cmake --install build` needs no PYTHONPATH). Variables: BUILD_DIR, PYTHON, PYDIR, WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "install failed")
endif()
set(check "import softhd, numpy as np; assert softhd.__file__.startswith('${WORK_DIR}/prefix'), softhd.__file__; r = softhd.distance(np.eye(3), np.eye(3), method='nearest'); assert r.rho == 0.0")
execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${WORK_DIR}/prefix/${PYDIR}
  ${PYTHON} -c "${check}" WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "the installed package does not import")
endif()
execute_process(COMMAND ${PYTHON} -c "import sys; sys.exit('/usr/local/${PYDIR}' not in sys.path)"
  RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "/usr/local/${PYDIR} is not on ${PYTHON}'s sys.path: set SOFTHD_PYTHON_INSTALL_DIR")
endif()
