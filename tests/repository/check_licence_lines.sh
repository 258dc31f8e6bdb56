#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# usage: check_licence_lines.sh ROOT -- every source, build and script file under ROOT names its
# licence (an SPDX line within its first three lines), and none reads from outside the repository
# (a path to a folder beside the checkout). Lists the offenders and exits 1 when there are any.
set -euo pipefail
root=${1:?usage: check_licence_lines.sh ROOT}
cd "$root"
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files)
else
  mapfile -t files < <(find . -type f ! -path './build*' ! -path './.git/*' | sed 's|^\./||')
fi
# The pattern is spelled in two halves so that this script does not match itself.
beside="\.\./sha""red"
checked=() licensed=()
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  case "$f" in
    tests/data/*|*.md|*.json|*.pnbf|*.f32|*.png|LICENSE|.gitignore) continue ;;
    *.cpp|*.h|*.c|*.comp|*.geo|*.f90|*.cmake|*/CMakeLists.txt|CMakeLists.txt|*.in|*.sh|*.py|*.js|*.html|*.css|.ci/run)
      licensed+=("$f") ;;
  esac
  checked+=("$f")
done
# One awk over all the licensed files: those whose first three lines carry no SPDX line.
mapfile -t missing < <(awk 'FNR == 1 { if (NR > 1 && !found) print name; name = FILENAME; found = 0 }
  FNR <= 3 && /SPDX-License-Identifier: BSD-3-Clause/ { found = 1 }
  END { if (NR > 0 && !found) print name }' "${licensed[@]}")
mapfile -t outside < <(grep -lE "$beside" "${checked[@]}" || true)
status=0
if [ ${#missing[@]} -gt 0 ]; then
  printf 'no SPDX-License-Identifier line in the first three lines of:\n'; printf '  %s\n' "${missing[@]}"
  status=1
fi
if [ ${#outside[@]} -gt 0 ]; then
  printf 'reads a folder outside the repository:\n'; printf '  %s\n' "${outside[@]}"
  status=1
fi
[ $status -eq 0 ] && echo "licence lines and paths: ${#files[@]} files checked"
exit $status
