# SPDX-License-Identifier: Apache-2.0
# Helpers of the ctest drivers run_tests.cmake, run_example.cmake and
# run_consumers.cmake (cmake -P scripts).
set(ENV{DOTNET_CLI_TELEMETRY_OPTOUT} 1)
set(ENV{DOTNET_NOLOGO} 1)
set(ENV{DOTNET_SKIP_FIRST_TIME_EXPERIENCE} 1)
set(ENV{DOTNET_CLI_USE_MSBUILD_SERVER} 0)
set(ENV{MSBUILDDISABLENODEREUSE} 1)

# Restore's extra sources: the feed with the Flatline package, then the
# extra sources of the build (%3B-separated, as msbuild wants on a command
# line); the machine's NuGet configuration comes first anyway.
set(FLT_RESTORE_SOURCES "${FEED}")
if(EXTRA_SOURCES)
  string(APPEND FLT_RESTORE_SOURCES "%3B${EXTRA_SOURCES}")
endif()

# dotnet VERB ARGS... (no lingering build servers); fails the test on error.
function(flt_dotnet verb)
  execute_process(COMMAND ${DOTNET} ${verb} ${ARGN} -nodeReuse:false --disable-build-servers
                  RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "dotnet ${verb} failed (${rc})")
  endif()
endfunction()

# Runs a program; fails the test when it exits non-zero.
function(flt_run_checked what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc})")
  endif()
endfunction()

# The package exists in the feed and holds the RID's native files.
function(flt_check_package feed version rid)
  set(package ${feed}/Flatline.${version}.nupkg)
  if(NOT EXISTS ${package})
    message(FATAL_ERROR "${package} does not exist: build the dev preset (which packs the "
                        "Linux and the win64 natives) after the win64 one")
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E tar tf ${package} OUTPUT_VARIABLE listing
                  RESULT_VARIABLE rc)
  if(rc OR NOT listing MATCHES "runtimes/${rid}/native/")
    message(FATAL_ERROR "${package} has no runtimes/${rid}/native/: configure the dev preset "
                        "after building the win64 one (FLT_CSHARP_EXTRA_NATIVE)")
  endif()
endfunction()
