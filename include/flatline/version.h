// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - version of the headers.
 *
 * This file is the single source of truth for the version: CMake reads the
 * three numbers below when it configures the project.
 */
#ifndef FLATLINE_VERSION_H
#define FLATLINE_VERSION_H

#define FLT_VERSION_MAJOR 0
#define FLT_VERSION_MINOR 2
#define FLT_VERSION_PATCH 0

/** @def FLT_VERSION_MAJOR
 * The major version of the headers: while it is 0, a minor release may
 * change the ABI (CHANGELOG.md lists every change). */
/** @def FLT_VERSION_MINOR
 * The minor version of the headers. */
/** @def FLT_VERSION_PATCH
 * The patch version of the headers: a patch release keeps the ABI. */

/** One integer, MAJOR*10000 + MINOR*100 + PATCH, for `#if` comparisons. */
#define FLT_VERSION_NUMBER (FLT_VERSION_MAJOR * 10000 + FLT_VERSION_MINOR * 100 + FLT_VERSION_PATCH)

/** True when the headers are at least version major.minor.patch. */
#define FLT_VERSION_CHECK(major, minor, patch) \
  (FLT_VERSION_NUMBER >= ((major)*10000 + (minor)*100 + (patch)))

/** Helper of FLT_VERSION_STRING: the argument as a string literal. */
#define FLT_VERSION_STRINGIFY_(x) #x
/** Helper of FLT_VERSION_STRING: the expanded argument as a string literal. */
#define FLT_VERSION_STRINGIFY(x)  FLT_VERSION_STRINGIFY_(x)
/** "MAJOR.MINOR.PATCH" of the headers, a string literal. */
#define FLT_VERSION_STRING                 \
  FLT_VERSION_STRINGIFY(FLT_VERSION_MAJOR) \
  "." FLT_VERSION_STRINGIFY(FLT_VERSION_MINOR) "." FLT_VERSION_STRINGIFY(FLT_VERSION_PATCH)

#endif /* FLATLINE_VERSION_H */
