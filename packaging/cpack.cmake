# SPDX-License-Identifier: Apache-2.0
# The release packages CPack makes from a build (packaging/README.md):
#   Linux    a Debian package (cpack -G DEB): the library, the C headers,
#            the CMake and pkg-config files and the commands, under /usr
#   Windows  the SDK zip (cpack -G ZIP): bin/ (libflatline.dll and the
#            commands as .exe), lib/ (the MinGW and MSVC import libraries,
#            the .def, CMake and pkg-config files), include/
# packaging/build runs both on the builds the test command made. The
# testing tier (component "testing") is left out: production programs
# link libflatline only.
set(CPACK_PACKAGE_NAME "libflatline")
set(CPACK_PACKAGE_VENDOR "The libflatline authors")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_HOMEPAGE_URL "https://github.com/libflatline/libflatline")
set(CPACK_RESOURCE_FILE_LICENSE "${PROJECT_SOURCE_DIR}/LICENSE")
# One package of these components (a monolithic package would take every
# component, the testing tier's too).
set(CPACK_COMPONENTS_ALL Unspecified tools)
set(CPACK_COMPONENTS_GROUPING ALL_COMPONENTS_IN_ONE)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_ARCHIVE_COMPONENT_INSTALL ON)
set(CPACK_STRIP_FILES ON)  # the RelWithDebInfo library is 20+ MB with its debug information
set(CPACK_PACKAGE_CHECKSUM SHA256)
# the licences of what the binaries carry (NOTICE) go with them
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/NOTICE
        DESTINATION ${CMAKE_INSTALL_DOCDIR})

if(WIN32)
  set(CPACK_GENERATOR ZIP)
  set(CPACK_PACKAGE_FILE_NAME "flatline-${PROJECT_VERSION}-win64")
  set(CPACK_INCLUDE_TOPLEVEL_DIRECTORY ON)
  set(CPACK_COMPONENT_INCLUDE_TOPLEVEL_DIRECTORY ON)  # (the component install's own switch)
else()
  set(CPACK_GENERATOR DEB)
  set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
  set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # libflatline_X.Y.Z_amd64.deb
  set(CPACK_DEBIAN_PACKAGE_SECTION libs)
  set(CPACK_DEBIAN_PACKAGE_MAINTAINER "The libflatline authors <libflatline@users.noreply.github.com>")
  set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
      "Online flatness gauge for steel strip from a dual-line-laser sensor
 libflatline turns a dual-line-laser + camera sensor into an online flatness
 gauge: calibration, frame sources (USB3 Vision, GigE Vision), extraction,
 streaming Hermite reconstruction, flatness metrics and verdicts, behind a
 stable C ABI. This package holds the shared library, its C headers, its
 CMake (find_package(flatline)) and pkg-config files, and the commands
 flatline-camera and flatline-calibrate.")
  # The runtime libraries it links (OpenCV, libusb, expat, zlib, libstdc++)
  # from dpkg-shlibdeps, as Debian's own packages do.
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
endif()
include(CPack)
