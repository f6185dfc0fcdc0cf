# SPDX-License-Identifier: Apache-2.0
# ctest's csharp.xunit and csharp.xunit_win64: build the xunit.v3 suite (a
# test program) and run it.
#   -D DOTNET PROJECT ARTIFACTS VERSION EXTRA_SOURCES PACKAGES
#   Linux (no RID): -D PROPS (the binding's build properties): the suite
#     against the binding's project and the freshly built natives.
#   Windows: -D RID FEED EMULATOR: the suite against the Flatline package in
#     FEED (its runtimes/<RID>/native), published self-contained for RID
#     and run through EMULATOR (wine).
include(${CMAKE_CURRENT_LIST_DIR}/dotnet_common.cmake)
if(NOT RID)
  flt_dotnet(build ${PROJECT} -c Release ${PROPS})
  set(suite ${ARTIFACTS}/bin/Flatline.Tests/release/Flatline.Tests.dll)
  flt_run_checked("the C# suite" ${DOTNET} ${suite} -noColor)
else()
  flt_check_package(${FEED} ${VERSION} ${RID})
  file(REMOVE_RECURSE ${PACKAGES}/flatline)
  flt_dotnet(publish ${PROJECT} -c Release -r ${RID} --self-contained
             -p:FlatlinePackageVersion=${VERSION} -p:FlatlineArtifacts=${ARTIFACTS}
             -p:RestorePackagesPath=${PACKAGES}
             -p:FlatlineRestoreSources=${FLT_RESTORE_SOURCES})
  set(suite ${ARTIFACTS}/publish/Flatline.Tests/release_${RID}/Flatline.Tests.exe)
  flt_run_checked("the C# suite (${RID})" ${EMULATOR} ${suite} -noColor)
endif()
