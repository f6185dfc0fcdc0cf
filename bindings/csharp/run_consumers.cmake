# SPDX-License-Identifier: Apache-2.0
# ctest's csharp.frameworks: a .NET Framework 4.8 project and a .NET 8
# project build against the Flatline package in FEED; the net48 one takes
# its netstandard2.0 assembly and gets the win-x64 natives beside it, the
# net8.0 one takes its net8.0 assembly and runs here.
#   -D DOTNET CONSUMERS FEED PACKAGES ARTIFACTS VERSION EXTRA_SOURCES
include(${CMAKE_CURRENT_LIST_DIR}/dotnet_common.cmake)
file(REMOVE_RECURSE ${PACKAGES}/flatline)
set(restore -p:FlatlineVersion=${VERSION} -p:RestorePackagesPath=${PACKAGES}
            -p:FlatlineArtifacts=${ARTIFACTS}
            -p:FlatlineRestoreSources=${FLT_RESTORE_SOURCES})

# Which of the package's assemblies a project compiled against: the
# "compile" asset of Flatline in its project.assets.json.
function(compiled_against project out)
  file(READ ${ARTIFACTS}/obj/${project}/project.assets.json assets)
  # (Flatline's entry holds nested braces, its dependencies; only its own
  # compile asset names lib/<tfm>/Flatline.dll.)
  if(assets MATCHES "\"Flatline/${VERSION}\": {.*\"compile\": {[ \r\n]*\"lib/([^/]+)/Flatline.dll\"")
    set(${out} ${CMAKE_MATCH_1} PARENT_SCOPE)
  else()
    message(FATAL_ERROR "${project}: no Flatline ${VERSION} compile asset in its project.assets.json")
  endif()
endfunction()

flt_dotnet(build ${CONSUMERS}/net48/Net48Consumer.csproj -c Release ${restore})
compiled_against(Net48Consumer tfm)
# The Windows natives come with the package when a Windows build made them
# (in .ci/test always): then they must be beside the program.
execute_process(COMMAND ${CMAKE_COMMAND} -E tar tf ${FEED}/Flatline.${VERSION}.nupkg
                OUTPUT_VARIABLE listing)
set(out ${ARTIFACTS}/bin/Net48Consumer/release_win-x64)
set(expected Net48Consumer.exe Flatline.dll)
set(natives "the package has no win-x64 natives (no Windows build packed)")
if(listing MATCHES "runtimes/win-x64/native/")
  list(APPEND expected libflatline.dll flatline_csharp.dll)
  set(natives "libflatline.dll and flatline_csharp.dll beside it")
endif()
foreach(f ${expected})
  if(NOT EXISTS ${out}/${f})
    message(FATAL_ERROR "net48: ${f} is not in the output folder ${out}")
  endif()
endforeach()
message(STATUS "net48: built against Flatline ${tfm}; Net48Consumer.exe with ${natives}")
if(NOT tfm STREQUAL "netstandard2.0")
  message(FATAL_ERROR "net48 compiled against ${tfm}, not netstandard2.0")
endif()

flt_dotnet(build ${CONSUMERS}/net8.0/Net8Consumer.csproj -c Release ${restore})
compiled_against(Net8Consumer tfm)
if(NOT tfm STREQUAL "net8.0")
  message(FATAL_ERROR "net8.0 compiled against ${tfm}, not net8.0")
endif()
execute_process(COMMAND ${DOTNET} ${ARTIFACTS}/bin/Net8Consumer/release/Net8Consumer.dll
                OUTPUT_VARIABLE output RESULT_VARIABLE rc)
message(STATUS "net8.0: built against Flatline ${tfm}, ran: ${output}")
if(rc)
  message(FATAL_ERROR "Net8Consumer failed (${rc})")
endif()
