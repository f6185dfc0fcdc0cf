#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Asserts that a shared library exports only flt_* symbols: everything else
# (the C++ runtime, Eigen, OpenCV, libusb, zlib, expat, the library's own
# C++ internals) must stay hidden, or it would clash with the vendor's copies
# inside the same HMI process.
#   usage: check_exports.sh path/to/libflatline.so [FORBIDDEN_PREFIX...]
# Each FORBIDDEN_PREFIX (e.g. flt_u3v_sim_: the test doubles, which live in
# libflatline_testing) must not start any exported symbol either.
set -eu
lib=${1:?usage: check_exports.sh LIBRARY [FORBIDDEN_PREFIX...]}
shift
if ! command -v nm >/dev/null 2>&1; then
  echo "SKIP: nm (binutils) not found"; exit 77
fi
# Defined dynamic symbols, without the ELF version nodes (type V/A, e.g.
# FLATLINE_0) that are markers rather than code or data.
all=$(nm -D --defined-only "$lib" | awk '$2 != "A" && $2 != "V" {print $3}')
count=$(printf '%s\n' "$all" | grep -c . || true)
bad=$(printf '%s\n' "$all" | grep -v '^flt_' | grep . || true)
if [ -n "$bad" ]; then
  echo "FAIL: $lib exports symbols outside flt_*:"
  printf '  %s\n' $bad
  echo "Give them hidden visibility (only FLT_API functions are exported)."
  exit 1
fi
for prefix in "$@"; do
  found=$(printf '%s\n' "$all" | grep "^$prefix" || true)
  if [ -n "$found" ]; then
    echo "FAIL: $lib exports symbols it must not ($prefix*):"
    printf '  %s\n' $found
    exit 1
  fi
done
if [ "$count" -lt 1 ]; then
  echo "FAIL: $lib exports no flt_* symbol at all"; exit 1
fi
echo "OK: $lib exports $count symbols, all flt_*${1:+, none starting with $*}"
