#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Runs viewer_browser_test.mjs, or exits 77 (ctest: skipped) naming what is missing.
# usage: run_browser_test.sh PENUMBRA_VIEW EXAMPLE_PROGRAM OUT_DIR [PENUMBRA_REPLAY]
dir=$(cd "$(dirname "$0")" && pwd)
chromium=$(command -v chromium)
if ! command -v node >/dev/null || [ -z "$chromium" ] || [ ! -d "$dir/node_modules/playwright-core" ]; then
  echo "viewer.browser skipped: needs node, chromium and tests/viewer/browser/node_modules (bash scripts/setup.sh)"
  exit 77
fi
exec node "$dir/viewer_browser_test.mjs" "$1" "$2" "$3" "$chromium" "${4:-none}"
