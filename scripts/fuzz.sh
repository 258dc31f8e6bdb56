#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# scripts/fuzz.sh [SECONDS] -- builds the parsers' libFuzzer harnesses (tests/fuzz, described in
# tests/README.md) with clang, AddressSanitizer and UndefinedBehaviorSanitizer in build-fuzz, then
# runs each for SECONDS (default 60; as many at once as there are cores) on a copy of its seeds and
# regression inputs, in a temporary folder (nothing is written into the repository; inputs that
# crash are kept in build-fuzz/artifacts/). Leak detection is on. Prints one line per harness (executions, and the
# cov/ft that libFuzzer reached) and exits 1 when any harness crashed, leaked, hung (-timeout=10),
# ran out of memory (-rss_limit_mb=2048) or hit undefined behaviour.
# Needs what scripts/setup.sh installs, and clang 14 or later with its libFuzzer runtime.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
build=build-fuzz
case "$seconds" in '' | *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS]" >&2; exit 2 ;; esac

# name and -max_len per harness: a little above the largest seed, so mutations can grow it.
harnesses=(config cinema_csv steps_csv stored_mesh coordinate_log field_file netcdf_size input_series request_path spacemouse)
declare -A max_len=([config]=8192 [cinema_csv]=4096 [steps_csv]=2048 [stored_mesh]=4096 [coordinate_log]=1024 [field_file]=16384
                    [netcdf_size]=8192 [input_series]=4096 [request_path]=2048 [spacemouse]=1024)
declare -A dict=([config]=tests/fuzz/config.dict)

# Coverage instrumentation and both sanitizers on every library; -fsanitize=fuzzer (libFuzzer's
# main) is added to the harnesses' link by tests/fuzz/CMakeLists.txt. No NDEBUG: the internal
# assertions are checked too. Static libraries, so each harness is one self-contained program.
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
start=$(date +%s)
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DBUILD_SHARED_LIBS=OFF -DPNB_BUILD_FUZZERS=ON -DPNB_BUILD_TESTS=OFF -DPNB_BUILD_EXAMPLES=OFF \
  -DPNB_BUILD_BENCHMARKS=OFF -DPNB_ENABLE_FORTRAN=OFF -DPNB_ENABLE_EGL=OFF -DPNB_ENABLE_VIEWER=OFF >/dev/null
targets=()
for h in "${harnesses[@]}"; do targets+=("pnb_fuzz_$h"); done
cmake --build "$build" --target "${targets[@]}"
built=$(date +%s)
echo "fuzz.sh: build took $((built - start)) s"

work=$(mktemp -d "${TMPDIR:-/tmp}/pnb-fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$build/artifacts"
export TMPDIR="$work"  # the harnesses' own temporary files
export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:allocator_may_return_null=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# One harness: its run, then its summary line in $work/$h.line (FAILED and the first lines of the
# report on stderr when it failed).
run_harness() {
  local h=$1 corpus="$work/corpus-$h" log="$work/$h.log" rc=0
  mkdir -p "$corpus"
  cp tests/fuzz/seeds/"$h"/* "$corpus"/
  if [ -d tests/fuzz/regressions/"$h" ] && [ -n "$(ls -A tests/fuzz/regressions/"$h")" ]; then
    cp tests/fuzz/regressions/"$h"/* "$corpus"/
  fi
  local seeds
  seeds=$(ls "$corpus" | wc -l)
  local args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len="${max_len[$h]}" -print_final_stats=1
              -detect_leaks=1 -artifact_prefix="$build/artifacts/$h-")
  if [ -n "${dict[$h]:-}" ]; then args+=(-dict="${dict[$h]}"); fi
  "$build/tests/fuzz/pnb_fuzz_$h" "${args[@]}" "$corpus" >"$log" 2>&1 || rc=$?
  local execs last cov ft line
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  last=$(grep -E '^#[0-9]+.* cov: ' "$log" | tail -n 1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  line=$(printf '%-13s %10s executions  cov: %-6s ft: %-6s corpus %s -> %s' "$h" "${execs:-?}" "${cov:-?}" "${ft:-?}" \
         "$seeds" "$(ls "$corpus" | wc -l)")
  if [ "$rc" -ne 0 ] || grep -qE 'runtime error:|ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)' "$log"; then
    line="$line  FAILED (exit $rc; inputs in $build/artifacts/)"
    grep -E 'runtime error:|ERROR:|SUMMARY:|Test unit written|^    #[0-9]+ ' "$log" | head -n 40 >&2 || true
  fi
  echo "$line" >"$work/$h.line"
}

# As many harnesses at once as there are cores: a libFuzzer run is one process on one core (only
# field_file's page decodes use the thread pool), so the run takes a fraction of the time.
parallel=$(nproc)
for h in "${harnesses[@]}"; do
  echo "fuzz.sh: $h for $seconds s ..."
  run_harness "$h" &
  while [ "$(jobs -rp | wc -l)" -ge "$parallel" ]; do wait -n || true; done
done
wait
failed=()
summary=()
for h in "${harnesses[@]}"; do
  line=$(cat "$work/$h.line" 2>/dev/null || echo "$h  FAILED (no result)")
  [[ "$line" == *FAILED* ]] && failed+=("$h")
  summary+=("$line")
done
echo "fuzz.sh: runs took $(($(date +%s) - built)) s ($seconds s per harness, $parallel at once)"
printf '%s\n' "${summary[@]}"
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz.sh: no crash, leak, hang, out-of-memory or undefined behaviour in ${#harnesses[@]} harnesses"
