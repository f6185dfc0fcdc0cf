#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the libFuzzer harnesses for a bounded time under AddressSanitizer +
# UndefinedBehaviorSanitizer, in the asan preset's build (clang, the whole
# project with -fsanitize=fuzzer-no-link,address,undefined: the same tree
# the C tests run in under the sanitizers, so CI compiles it once); fails on
# any crash, sanitizer report, leak, timeout (10 s per input) or
# out-of-memory (2 GB). See tests/fuzz/README.md.
#   tests/fuzz/run.sh [harness...]     (default: all twelve)
#   FUZZ_SECONDS=20   seconds per harness
#   FUZZ_SEED=1       libFuzzer's seed: fixed, so CI explores the same inputs
#                     each run (a red CI is reproducible); 0 = random, for
#                     exploratory runs
#   FUZZ_JOBS=2       harnesses run at once (and build parallelism)
# New inputs libFuzzer finds go to build/asan/fuzz-corpus/<harness> (not the
# committed seeds); a crash leaves build/asan/fuzz-artifacts/<harness>-crash-*:
# copy it into tests/fuzz/regressions/<harness>/ so ctest replays it.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
seconds=${FUZZ_SECONDS:-20}
seed=${FUZZ_SEED:-1}
build=build/asan
jobs=${FUZZ_JOBS:-2}
harnesses=("$@")
((${#harnesses[@]})) || harnesses=(calib_load extractor recon genicam u3v gauge chain source_faults gvsp gvcp json record)

command -v clang >/dev/null || { echo "fuzz: clang not found (apt-get install clang libclang-rt-14-dev)"; exit 1; }
cmake --preset asan >/dev/null
targets=()
for h in "${harnesses[@]}"; do targets+=(--target "fuzz_$h"); done
cmake --build "$build" -j"$jobs" "${targets[@]}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
mkdir -p "$build/fuzz-artifacts"

# One harness; its log in $build/fuzz_<h>.log, its exit status in .status.
fuzz_one() {
  local h=$1 log="$build/fuzz_$1.log" status=0
  mkdir -p "$build/fuzz-corpus/$h"
  "$build/tests/fuzz/fuzz_$h" -max_total_time="$seconds" -seed="$seed" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$build/fuzz-artifacts/$h-" \
    "$build/fuzz-corpus/$h" "tests/fuzz/corpus/$h" >"$log" 2>&1 || status=$?
  echo "$status" >"$log.status"
}

# $jobs harnesses at a time (each is one process on one core); the results
# are printed in the harnesses' order once all have run.
echo "fuzz: ${#harnesses[@]} harnesses, ${seconds} s each, $jobs at a time"
running=0
for h in "${harnesses[@]}"; do
  if ((running >= jobs)); then
    wait -n || true
    running=$((running - 1))
  fi
  fuzz_one "$h" &
  running=$((running + 1))
done
wait

failed=()
for h in "${harnesses[@]}"; do
  log="$build/fuzz_$h.log"
  echo "== fuzz_$h: ${seconds} s =="
  if [[ "$(cat "$log.status" 2>/dev/null)" == 0 ]]; then
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov:" "$log" | tail -3
  else
    echo "fuzz_$h FAILED; the report:"
    grep -E -A25 "ERROR|==[0-9]+==|runtime error|deadly signal|Test unit written" "$log" | head -60
    failed+=("$h")
  fi
done
if ((${#failed[@]})); then
  echo "fuzz: crashes in ${failed[*]}; inputs in $build/fuzz-artifacts/"
  exit 1
fi
echo "fuzz: ${#harnesses[@]} harnesses, ${seconds} s each, no crash"
