#!/usr/bin/env bash
# Runs a1, a3, c1, d2, b3 and n1 with two robotperf builds and compares their results files
# field by field (scripts/same-results.py): a change that should not change behaviour, such as a
# refactoring, must pass. Usage:
#   scripts/check-same-results.sh BEFORE/robotperf AFTER/robotperf [OUT_DIR]
# Rates are low enough that a 2-core machine loses no message: a lost message changes counts and
# accuracy figures, and shows as a difference (rerun on a quieter machine).
set -euo pipefail
if [[ $# -lt 2 ]]; then
  sed -n '2,6p' "$0" >&2
  exit 2
fi
before=$1 after=$2
out=${3:-$(mktemp -d)}
here=$(cd "$(dirname "$0")" && pwd)
runs=("a1 --count 40" "a3 --rate 5 --count 20" "c1 --count 4" "d2 --count 200"
  "b3 --rate 5 --count 20" "n1 --count 200")
failed=0
for run in "${runs[@]}"; do
  id=${run%% *}
  for side in before after; do
    binary=$before
    [[ $side == after ]] && binary=$after
    mkdir -p "$out/$side"
    # Exit 3 (an invalid result) is a result too: c1 at 4 goals has too few samples.
    # shellcheck disable=SC2086
    "$binary" run $run --output "$out/$side/$id" >"$out/$side/$id.txt" 2>&1 || [[ $? -eq 3 ]] || {
      echo "$id: $side failed (see $out/$side/$id.txt)"
      failed=1
      continue 2
    }
  done
  if python3 "$here/same-results.py" "$out"/before/"$id"/*.json "$out"/after/"$id"/*.json; then
    echo "$id: same"
  else
    echo "$id: DIFFERENT"
    failed=1
  fi
done
echo "results in $out"
exit $failed
