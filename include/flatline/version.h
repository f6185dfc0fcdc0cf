// SPDX-License-Identifier: Apache-2.0
/*
 * libflatline - version of the headers.
 *
 * This file is the single source of truth for the version: CMake reads the
 * three numbers below when it configures the project.
 */
#ifndef FLATLINE_VERSION_H
#define FLATLINE_VERSION_H

#define FLT_VERSION_MAJOR 0
#define FLT_VERSION_MINOR 1
#define FLT_VERSION_PATCH 0

/* One integer, MAJOR*10000 + MINOR*100 + PATCH, for #if comparisons. */
#define FLT_VERSION_NUMBER (FLT_VERSION_MAJOR * 10000 + FLT_VERSION_MINOR * 100 + FLT_VERSION_PATCH)

/* True when the headers are at least version major.minor.patch. */
#define FLT_VERSION_CHECK(major, minor, patch) \
  (FLT_VERSION_NUMBER >= ((major)*10000 + (minor)*100 + (patch)))

#define FLT_VERSION_STRINGIFY_(x) #x
#define FLT_VERSION_STRINGIFY(x)  FLT_VERSION_STRINGIFY_(x)
#define FLT_VERSION_STRING                 \
  FLT_VERSION_STRINGIFY(FLT_VERSION_MAJOR) \
  "." FLT_VERSION_STRINGIFY(FLT_VERSION_MINOR) "." FLT_VERSION_STRINGIFY(FLT_VERSION_PATCH)

#endif /* FLATLINE_VERSION_H */
