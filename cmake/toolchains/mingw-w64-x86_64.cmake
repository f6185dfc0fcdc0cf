# SPDX-License-Identifier: Apache-2.0
# Cross build for Windows x64 with Debian's MinGW-w64 (the posix-thread
# variant, for std::thread), against the static libraries .ci/win64-deps
# builds; ctest runs the Windows programs under wine (wine-run beside this
# file). The win64 preset uses this file:
#
#   bash .ci/win64-deps && cmake --preset win64 && cmake --build --preset win64
#   ctest --preset win64
#
# FLT_WIN64_DEPS (cache or environment) names the dependency prefix; by
# default it is the one .ci/win64-deps --prefix prints.
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR AMD64)
set(_flt_triple x86_64-w64-mingw32)
set(CMAKE_C_COMPILER ${_flt_triple}-gcc-posix)
set(CMAKE_CXX_COMPILER ${_flt_triple}-g++-posix)
set(CMAKE_RC_COMPILER ${_flt_triple}-windres)
set(CMAKE_DLLTOOL ${_flt_triple}-dlltool)

if(NOT FLT_WIN64_DEPS AND DEFINED ENV{FLT_WIN64_DEPS})
  set(FLT_WIN64_DEPS "$ENV{FLT_WIN64_DEPS}")
endif()
if(NOT FLT_WIN64_DEPS)
  execute_process(
    COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/../../.ci/win64-deps --prefix
    OUTPUT_VARIABLE FLT_WIN64_DEPS OUTPUT_STRIP_TRAILING_WHITESPACE)
endif()
if(NOT EXISTS "${FLT_WIN64_DEPS}/.complete")
  message(FATAL_ERROR "The Windows dependencies are not built in '${FLT_WIN64_DEPS}': "
                      "run `bash .ci/win64-deps` first (or set FLT_WIN64_DEPS)")
endif()
set(FLT_WIN64_DEPS "${FLT_WIN64_DEPS}" CACHE PATH "Prefix of the static Windows dependencies")
# try_compile projects see the same prefix.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES FLT_WIN64_DEPS)

# (Appended: a consumer may pass roots of its own, e.g. an install prefix.)
list(APPEND CMAKE_FIND_ROOT_PATH ${FLT_WIN64_DEPS} /usr/${_flt_triple})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# Static zlib (MinGW's own package has both; the DLL would have to ship).
set(ZLIB_USE_STATIC_LIBS ON)
# pkg-config (libusb, cmocka) reads only the prefix's .pc files.
set(ENV{PKG_CONFIG_LIBDIR} "${FLT_WIN64_DEPS}/lib/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "")

# Every program and DLL self-contained: the C and C++ runtimes and
# winpthread linked in, so nothing but Windows' own DLLs is needed beside
# them (a missing DLL under wine is a hang or a silent exit, not a message).
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "-static")
set(CMAKE_MODULE_LINKER_FLAGS_INIT "-static")

set(CMAKE_CROSSCOMPILING_EMULATOR ${CMAKE_CURRENT_LIST_DIR}/wine-run)
