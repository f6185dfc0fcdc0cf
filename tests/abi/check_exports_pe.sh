#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Windows: asserts that libflatline.dll exports exactly the FLT_API
# functions of the public headers, by name, and nothing else (no symbol of
# the statically linked C++ runtime, OpenCV, libusb, zlib or expat), and
# that the .def file and the MSVC import library (libflatline.lib) list
# the same functions. (test_bad_input checks at run time that every export
# is code.)
#   usage: check_exports_pe.sh OBJDUMP LIBFLATLINE.DLL INCLUDE_DIR [DEF] [LIB]
set -eu
objdump=${1:?usage: check_exports_pe.sh OBJDUMP DLL INCLUDE_DIR [DEF] [LIB]}
dll=${2:?}
include=${3:?}
def=${4:-}
implib=${5:-}
command -v "$objdump" >/dev/null 2>&1 || { echo "SKIP: $objdump not found"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# Declared: "FLT_API ... FLT_CALL flt_name(" in every public header (a
# declaration may span lines; one per ';'). Only FLT_API ones: a companion
# library's header declares its own functions with its own export macro.
cat "$include"/flatline/*.h | tr '\n' ' ' | tr ';' '\n' |
  grep -E '(^|[^A-Za-z0-9_])FLT_API([^A-Za-z0-9_]|$)' |
  grep -o 'FLT_CALL *flt_[A-Za-z0-9_]* *(' | sed 's/FLT_CALL *//; s/ *(//' | sort -u >"$tmp/declared"
# Exported: the names of the export table ("[Ordinal/Name Pointer] Table").
"$objdump" -p "$dll" | awk '
  /\[Ordinal\/Name Pointer\] Table/ { table = 1; next }
  table && /^[ \t]*\[ *[0-9]+\]/ { print $NF; next }
  table { table = 0 }' | sort >"$tmp/exported"

status=0
if ! [ -s "$tmp/declared" ]; then
  echo "FAIL: no FLT_API function found in $include/flatline"; exit 1
fi
extra=$(comm -13 "$tmp/declared" "$tmp/exported")
missing=$(comm -23 "$tmp/declared" "$tmp/exported")
if [ -n "$extra" ]; then
  echo "FAIL: $dll exports what no public header declares:"
  printf '  %s\n' $extra
  echo "Only FLT_API functions may be exported."
  status=1
fi
if [ -n "$missing" ]; then
  echo "FAIL: $dll does not export these FLT_API functions:"
  printf '  %s\n' $missing
  status=1
fi
if [ -n "$def" ]; then
  # EXPORTS section of the .def: "    name @ordinal" lines.
  awk '/^EXPORTS/ { e = 1; next } e && NF { print $1 }' "$def" | sort >"$tmp/def"
  if ! cmp -s "$tmp/def" "$tmp/exported"; then
    echo "FAIL: $def does not list exactly the DLL's exports:"
    diff "$tmp/def" "$tmp/exported" | sed 's/^/  /' || true
    status=1
  fi
fi
if [ -n "$implib" ]; then
  # The import library's symbols: __imp_<name> for each function.
  nm=$(dirname "$objdump")/$(basename "$objdump" | sed 's/objdump$/nm/')
  command -v "$nm" >/dev/null 2>&1 || nm=nm
  "$nm" "$implib" 2>/dev/null | awk '$3 ~ /^__imp_/ { sub(/^__imp_/, "", $3); print $3 }' |
    sort -u >"$tmp/implib"
  if ! cmp -s "$tmp/implib" "$tmp/exported"; then
    echo "FAIL: $implib does not import exactly the DLL's exports:"
    diff "$tmp/implib" "$tmp/exported" | sed 's/^/  /' || true
    status=1
  fi
fi
[ "$status" -eq 0 ] || exit "$status"
echo "OK: $(basename "$dll") exports $(wc -l <"$tmp/exported") functions, exactly the FLT_API ones of the headers${def:+; the .def}${implib:+ and the MSVC import library} agree"
