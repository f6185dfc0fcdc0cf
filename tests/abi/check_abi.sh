#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Compares a built libflatline.so with the committed ABI baseline
# (tests/abi/libflatline.abi) and fails on any change that breaks binaries
# built against the baseline. Policy and baseline updates: tests/abi/README.md.
#   usage: check_abi.sh LIBRARY BASELINE SOURCE_ROOT
# Exit: 0 compatible, 1 incompatible (or a tool error), 77 skipped (no
# abidiff: install the Debian package abigail-tools; .ci/deps does).
set -u
lib=${1:?usage: check_abi.sh LIBRARY BASELINE SOURCE_ROOT}
baseline=${2:?usage: check_abi.sh LIBRARY BASELINE SOURCE_ROOT}
root=${3:?usage: check_abi.sh LIBRARY BASELINE SOURCE_ROOT}
here=$(cd "$(dirname "$0")" && pwd)

if ! command -v abidiff >/dev/null 2>&1; then
  echo "SKIP: abidiff not found; install it with: apt-get install abigail-tools"
  echo "      (.ci/deps installs it, so CI runs this check)"
  exit 77
fi
if [ ! -f "$baseline" ]; then
  echo "FAIL: no baseline at $baseline; create it with $here/update_baseline.sh"
  exit 1
fi

# Without DWARF (a Release build) libabigail sees only the ELF symbols: a
# removed function is still caught, a changed signature or enum value is not.
# The dev preset (RelWithDebInfo) and the asan preset (Debug) carry DWARF, and
# .ci/test runs both, so CI always does the full check.
if readelf -S "$lib" 2>/dev/null | grep -q '\.debug_info'; then
  mode=full
else
  mode=symbols
  echo "NOTE: $lib has no debug info (a Release build?): checking the exported"
  echo "      symbols only. The full check (signatures, enum values) needs a"
  echo "      build with -g: the dev or asan preset."
fi

# The build's side is dumped exactly as the baseline was (dump_abi.sh: public
# header types only, so the layout of the opaque handles, defined in
# lib/*.cpp, is not ABI), and the two XML files are compared (reading the
# library's whole DWARF in abidiff would take half a minute).
# --no-added-syms: adding functions is compatible (reported below as a note).
# Harmless changes (enumerators appended before the MAX_ENUM_ sentinel) are
# filtered out by abidiff's default suppression of harmless changes.
current=$(mktemp "${TMPDIR:-/tmp}/flatline-abi.XXXXXX")
trap 'rm -f "$current"' EXIT
if ! sh "$here/dump_abi.sh" "$lib" "$root" > "$current"; then
  echo "FAIL: abidw could not read $lib"; exit 1
fi
report=$(abidiff --drop-private-types --no-added-syms "$baseline" "$current" 2>&1)
rc=$?
if [ $rc -ne 0 ]; then
  echo "FAIL: the ABI of $lib differs incompatibly from the baseline"
  echo "      $baseline (abidiff exit $rc):"
  echo "$report" | sed 's/^/  | /'
  echo
  echo "If the break is deliberate (a new SONAME: FLT_VERSION_MINOR bumped while"
  echo "MAJOR is 0, FLT_VERSION_MAJOR after; see tests/abi/README.md), record"
  echo "the new ABI with:"
  echo "  tests/abi/update_baseline.sh [build-dir]"
  echo "and commit tests/abi/libflatline.abi with the change."
  exit 1
fi

added=$(abidiff --drop-private-types "$baseline" "$current" 2>&1 |
        sed -n 's/^[[:space:]]*\[A\] //p')
if [ -n "$added" ]; then
  echo "NOTE: functions added since the baseline (compatible):"
  echo "$added" | sed 's/^/  /'
  echo "  Record them with tests/abi/update_baseline.sh when the release is cut,"
  echo "  so that removing them later is caught."
fi
nfun=$(grep -c "<elf-symbol name='flt_" "$baseline")
echo "OK: ABI of $lib is compatible with the baseline ($nfun flt_* symbols; $mode check)"
exit 0
