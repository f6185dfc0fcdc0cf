#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Records the current ABI of libflatline as the baseline the abi.abidiff test
# compares against. Run it only for a deliberate ABI change (see README.md):
#   tests/abi/update_baseline.sh [BUILD_DIR]      (default: build/dev)
# BUILD_DIR must be configured with debug info (the dev preset,
# RelWithDebInfo): `cmake --preset dev` first if it does not exist.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build/dev}
command -v abidw >/dev/null 2>&1 || {
  echo "abidw not found: apt-get install abigail-tools" >&2; exit 1; }
cmake --build "$build" --target flatline -j2
lib=$(find "$build/lib" -maxdepth 1 -name 'libflatline.so.*.*.*' | head -n 1)
[ -n "$lib" ] || { echo "no libflatline.so.X.Y.Z in $build/lib" >&2; exit 1; }
readelf -S "$lib" | grep -q '\.debug_info' || {
  echo "$lib has no debug info: use a RelWithDebInfo (dev preset) build" >&2
  exit 1; }
sh "$root/tests/abi/dump_abi.sh" "$lib" "$root" > "$root/tests/abi/libflatline.abi"
echo "wrote tests/abi/libflatline.abi from $lib:"
grep -c "<elf-symbol name='flt_" "$root/tests/abi/libflatline.abi" |
  sed 's/$/ flt_* symbols/'
