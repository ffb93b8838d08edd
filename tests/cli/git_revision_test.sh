#!/usr/bin/env bash
# cmake/GitRevision.cmake, which every build runs: the header names the tree's revision after each
# commit and edit, and is left untouched (so nothing recompiles) while the revision stays.
# Usage: git_revision_test.sh <path of GitRevision.cmake>
set -euo pipefail
script=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# A tree without .git must not find a repository above it.
export GIT_CEILING_DIRECTORIES=$work
fail() {
  echo "FAIL: $*" >&2
  [[ -f "$work/out.hpp" ]] && cat "$work/out.hpp" >&2
  exit 1
}
git_in() { git -C "$work/tree" -c user.name=test -c user.email=test@example.com "$@"; }
write_header() { cmake -DSOURCE_DIR="$work/tree" -DOUTPUT="$work/out.hpp" -P "$script"; }
names() { grep -q "kGitRevision = \"$1\";" "$work/out.hpp" || fail "the header does not name $1"; }

mkdir "$work/tree"
git_in init -q
echo one >"$work/tree/file"
git_in add file
git_in commit -qm one
write_header
names "$(git_in rev-parse --short=12 HEAD)"

before=$(stat -c %y "$work/out.hpp")
write_header
[[ "$(stat -c %y "$work/out.hpp")" == "$before" ]] || fail "rewritten with the revision unchanged"

echo edited >"$work/tree/file"
write_header
names "$(git_in rev-parse --short=12 HEAD)-dirty"

git_in commit -qam two
write_header
names "$(git_in rev-parse --short=12 HEAD)"

rm -rf "$work/tree/.git"
write_header
names unknown
echo "ok"
