#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Asserts that a shared library exports only flt_* symbols: everything else
# (the C++ runtime, Eigen, OpenCV, libusb, zlib, expat, the library's own
# C++ internals) must stay hidden, or it would clash with the vendor's copies
# inside the same HMI process.
#   usage: check_exports.sh path/to/libflatline.so
set -eu
lib=${1:?usage: check_exports.sh LIBRARY}
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
if [ "$count" -lt 1 ]; then
  echo "FAIL: $lib exports no flt_* symbol at all"; exit 1
fi
echo "OK: $lib exports $count symbols, all flt_*"
