#!/usr/bin/env bash
# Writes robotperf's man page from its help: scripts/man-page.sh ROBOTPERF OUT.1
# help2man makes the page from `robotperf --help` and `--version`; a COMMANDS section adds each
# command's own help (`robotperf help COMMAND`), so that the page is as current as the binary.
set -euo pipefail
exe=$1
out=$2
include=$(mktemp)
trap 'rm -f "$include"' EXIT

# roff: a backslash is \e, and a line starting with . or ' would be a request.
as_roff() { sed -e 's/\\/\\e/g' -e "s/^\\([.']\\)/\\\\\\&\\1/"; }

{
  echo "[COMMANDS]"
  "$exe" --help | awk '/^Subcommands:/ { on = 1; next } on && /^  [a-z]/ { print $1 }' |
    while read -r verb; do
      echo ".SS $verb"
      echo ".nf"
      "$exe" help "$verb" | as_roff
      echo ".fi"
    done
  echo "[SEE ALSO]"
  echo "The manual: docs/ in the source tree (built with mkdocs), and README.md."
} >"$include"

mkdir -p "$(dirname "$out")"
help2man --no-info --no-discard-stderr \
  --name "benchmarking suite for robotics computing (ROS 2 graphs, black-box and grey-box)" \
  --version-string "robotperf $("$exe" --version)" \
  --include "$include" --output "$out.tmp" "$exe"
mv "$out.tmp" "$out"
