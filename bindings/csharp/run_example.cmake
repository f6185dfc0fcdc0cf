# SPDX-License-Identifier: Apache-2.0
# ctest's csharp.example: restore the example against the freshly packed
# Flatline package (local feed + offline folder), then run it.
# -D DOTNET PROJECT FEED OFFLINE PACKAGES ARTIFACTS VERSION
file(REMOVE_RECURSE ${PACKAGES}/flatline)
set(ENV{DOTNET_CLI_TELEMETRY_OPTOUT} 1)
set(ENV{DOTNET_NOLOGO} 1)
set(ENV{DOTNET_CLI_USE_MSBUILD_SERVER} 0)
set(ENV{MSBUILDDISABLENODEREUSE} 1)
set(props -p:FlatlineVersion=${VERSION} -p:FlatlineArtifacts=${ARTIFACTS}
          -p:RestorePackagesPath=${PACKAGES})
execute_process(
  COMMAND ${DOTNET} restore ${PROJECT} --source ${FEED} --source ${OFFLINE}
          ${props} -nodeReuse:false --disable-build-servers
  RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "dotnet restore of the example failed (${rc})")
endif()
execute_process(
  COMMAND ${DOTNET} build ${PROJECT} -c Release --no-restore ${props}
          -nodeReuse:false --disable-build-servers
  RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "dotnet build of the example failed (${rc})")
endif()
# The app runs from its output folder; the native files come from the
# package's runtimes/<rid>/native/ through the app's deps.json.
execute_process(
  COMMAND ${DOTNET} ${ARTIFACTS}/bin/FlatlineExample/release/FlatlineExample.dll
  RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "the example failed (${rc})")
endif()
