#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# scripts/thread_sanitize.sh [BUILD_DIR] -- builds the tests of the code that runs on several
# threads at once with ThreadSanitizer and runs them; any data race or lock-order report fails
# the run. That code: the thread pool, the pager's background loads and its page recycling, the
# streaming encoder's background thread, the field files those two meet in, the in-situ context
# (its store and kill-safe writes), and penumbra-view's server where it is built. The decoders'
# and renderers' own tests are left to the other builds: they reach threads only through the
# pool, which its own tests cover here, and would take many minutes more under the sanitizer.
# Needs what scripts/setup.sh installs. BUILD_DIR defaults to build-tsan.
#
# One test is left out, for a reason of the tool: ThreadPool.AForkedChildStillRunsOnSeveralThreads
# starts threads in a child forked from a process with threads, which ThreadSanitizer refuses
# ("starting new threads after multi-threaded fork is not supported").
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-tsan}
# The sanitizer's runtime cannot start under some kernels' address-space layouts (more random
# bits than it knows): probe once, and say so rather than fail on a program with no race.
probe=$(mktemp -d)
echo 'int main(void) { return 0; }' >"$probe/probe.c"
if ! { cc -fsanitize=thread "$probe/probe.c" -o "$probe/probe" && "$probe/probe"; } >/dev/null 2>&1; then
  echo "thread_sanitize.sh: ThreadSanitizer cannot run on this machine; skipped" >&2
  rm -rf "$probe"
  exit 0
fi
rm -rf "$probe"
flags="-fsanitize=thread -fno-omit-frame-pointer"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=thread"
targets=(penumbra_core_tests penumbra_compression_tests penumbra_insitu_tests)
# penumbra-view's server: its request threads, the render queue's worker, the pages' events.
viewer=$(grep -q '^PNB_ENABLE_VIEWER:BOOL=ON' "$build/CMakeCache.txt" && echo yes || true)
[ -n "$viewer" ] && targets+=(penumbra_viewer_tests)
cmake --build "$build" --target "${targets[@]}"
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1"
"$build/tests/unit/core/penumbra_core_tests" --gtest_filter='ThreadPool.*:-ThreadPool.AForkedChildStillRunsOnSeveralThreads'
"$build/tests/unit/compression/penumbra_compression_tests" --gtest_filter='Pager.*:StreamingEncoder.*:FieldFile.*'
"$build/tests/unit/insitu/penumbra_insitu_tests"
if [ -n "$viewer" ]; then "$build/tests/viewer/penumbra_viewer_tests"; fi
echo "thread_sanitize.sh: no report"
