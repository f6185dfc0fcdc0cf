# SPDX-License-Identifier: Apache-2.0
# Builds the API reference and fails unless every public symbol is
# documented: Doxygen with warnings as errors, then check_documented.py on
# its XML (enumerators). Used by the `docs` target and the ctest docs.api.
#   cmake -DDOXYGEN=... -DPYTHON=... -DDOXYFILE=... -DOUTPUT=... -DCHECK=... -P run_doxygen.cmake
foreach(_v DOXYGEN PYTHON DOXYFILE OUTPUT CHECK)
  if(NOT DEFINED ${_v})
    message(FATAL_ERROR "run_doxygen.cmake: ${_v} is not set")
  endif()
endforeach()
# A header removed since the last run must not leave its XML behind.
file(REMOVE_RECURSE "${OUTPUT}/xml")
execute_process(COMMAND "${DOXYGEN}" "${DOXYFILE}" RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "API reference: Doxygen failed (warnings above: every public "
                      "function, type and macro needs a /** ... */ comment; see CONTRIBUTING.md)")
endif()
execute_process(COMMAND "${PYTHON}" "${CHECK}" "${OUTPUT}/xml" RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "API reference: undocumented enumerators (above)")
endif()
message(STATUS "API reference: ${OUTPUT}/html/index.html")
