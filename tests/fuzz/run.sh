#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the libFuzzer harnesses with Debian's clang and runs each for a
# bounded time under AddressSanitizer + UndefinedBehaviorSanitizer; fails on
# any crash, sanitizer report, leak, timeout (10 s per input) or out-of-memory
# (2 GB). See tests/fuzz/README.md.
#   tests/fuzz/run.sh [harness...]     (default: all twelve)
#   FUZZ_SECONDS=20   seconds per harness
#   FUZZ_SEED=1       libFuzzer's seed: fixed, so CI explores the same inputs
#                     each run (a red CI is reproducible); 0 = random, for
#                     exploratory runs
#   FUZZ_BUILD=build/fuzz   build directory
#   FUZZ_JOBS=2       build parallelism
# New inputs libFuzzer finds go to $FUZZ_BUILD/corpus/<harness> (not the
# committed seeds); a crash leaves $FUZZ_BUILD/artifacts/<harness>-crash-*:
# copy it into tests/fuzz/regressions/<harness>/ so ctest replays it.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
seconds=${FUZZ_SECONDS:-20}
seed=${FUZZ_SEED:-1}
build=${FUZZ_BUILD:-build/fuzz}
jobs=${FUZZ_JOBS:-2}
harnesses=("$@")
((${#harnesses[@]})) || harnesses=(calib_load extractor recon genicam u3v gauge chain source_faults gvsp gvcp json record)

command -v clang >/dev/null || { echo "fuzz: clang not found (apt-get install clang libclang-rt-14-dev)"; exit 1; }
san="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_FLAGS="$san" -DCMAKE_CXX_FLAGS="$san" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DFLT_SANITIZED=ON -DFLT_BUILD_TESTS=ON -DFLT_BUILD_EXAMPLES=OFF -DFLT_FUZZ_LIBFUZZER=ON >/dev/null
targets=()
for h in "${harnesses[@]}"; do targets+=(--target "fuzz_$h"); done
cmake --build "$build" -j"$jobs" "${targets[@]}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
mkdir -p "$build/artifacts"
failed=()
for h in "${harnesses[@]}"; do
  mkdir -p "$build/corpus/$h"
  echo "== fuzz_$h: ${seconds} s =="
  log="$build/fuzz_$h.log"
  if "$build/tests/fuzz/fuzz_$h" -max_total_time="$seconds" -seed="$seed" -timeout=10 -rss_limit_mb=2048 \
       -print_final_stats=1 -artifact_prefix="$build/artifacts/$h-" \
       "$build/corpus/$h" "tests/fuzz/corpus/$h" >"$log" 2>&1; then
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov:" "$log" | tail -3
  else
    echo "fuzz_$h FAILED; the report:"
    grep -E -A25 "ERROR|==[0-9]+==|runtime error|deadly signal|Test unit written" "$log" | head -60
    failed+=("$h")
  fi
done
if ((${#failed[@]})); then
  echo "fuzz: crashes in ${failed[*]}; inputs in $build/artifacts/"
  exit 1
fi
echo "fuzz: ${#harnesses[@]} harnesses, ${seconds} s each, no crash"
