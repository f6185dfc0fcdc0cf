# SPDX-License-Identifier: Apache-2.0
# ctest's csharp.example and csharp.example_win64: restore the example
# against the freshly packed Flatline package (FEED + the extra sources),
# into a package folder of its own, build it and run it.
#   -D DOTNET PROJECT FEED PACKAGES ARTIFACTS VERSION EXTRA_SOURCES
#   Windows: -D RID EMULATOR COMPARE: the example runs on Linux and as a
#     self-contained RID program through EMULATOR (wine), each writing its
#     reconstructed rows (--dump), and COMPARE (a Python script) checks
#     that they agree within 1e-9 mm.
include(${CMAKE_CURRENT_LIST_DIR}/dotnet_common.cmake)
file(REMOVE_RECURSE ${PACKAGES}/flatline)
set(restore -p:FlatlineVersion=${VERSION} -p:RestorePackagesPath=${PACKAGES}
            -p:FlatlineRestoreSources=${FLT_RESTORE_SOURCES})
get_filename_component(name ${PROJECT} NAME_WE)

# The app runs from its output folder; the native files come from the
# package's runtimes/<rid>/native/ through the app's deps.json.
flt_dotnet(build ${PROJECT} -c Release -p:FlatlineArtifacts=${ARTIFACTS}/linux ${restore})
set(linux_app ${ARTIFACTS}/linux/bin/${name}/release/${name}.dll)
if(NOT RID)
  flt_run_checked("the example" ${DOTNET} ${linux_app})
  return()
endif()

flt_check_package(${FEED} ${VERSION} ${RID})
flt_run_checked("the example (Linux)" ${DOTNET} ${linux_app} --dump ${ARTIFACTS}/rows-linux.txt)
flt_dotnet(publish ${PROJECT} -c Release -r ${RID} --self-contained
           -p:FlatlineArtifacts=${ARTIFACTS}/${RID} ${restore})
set(win_app ${ARTIFACTS}/${RID}/publish/${name}/release_${RID}/${name}.exe)
flt_run_checked("the example (${RID})" ${EMULATOR} ${win_app} --dump ${ARTIFACTS}/rows-${RID}.txt)
find_program(PYTHON3 NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT PYTHON3)
  find_program(PYTHON3 python3 REQUIRED)
endif()
flt_run_checked("the comparison" ${PYTHON3} ${COMPARE} ${ARTIFACTS}/rows-linux.txt
                ${ARTIFACTS}/rows-${RID}.txt 1e-9 Linux ${RID})
