#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Writes the ABI of a libflatline.so as libabigail XML to stdout: what the
# flt_* symbols reach, public-header types only (the handles' layouts are
# private), no source locations, type ids hashed from the types and the
# source root removed, so two dumps differ only where the ABI does. Used by
# update_baseline.sh (the baseline) and check_abi.sh (the build's side).
#   usage: dump_abi.sh LIBRARY SOURCE_ROOT
set -eu
lib=${1:?usage: dump_abi.sh LIBRARY SOURCE_ROOT}
root=${2:?usage: dump_abi.sh LIBRARY SOURCE_ROOT}
abidw --exported-interfaces-only --headers-dir "$root/include/flatline" \
      --drop-private-types --no-corpus-path --no-comp-dir-path --no-show-locs \
      --type-id-style hash "$lib" | sed "s#$root/##g"
