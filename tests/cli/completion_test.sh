#!/usr/bin/env bash
# The completion scripts robotperf writes complete its commands, options, an option's choices and
# benchmark ids, in bash, and zsh reads its own without a syntax error.
# completion_test.sh ROBOTPERF
set -euo pipefail
exe=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$exe" completion bash >"$dir/robotperf.bash"
"$exe" completion zsh >"$dir/_robotperf"
zsh -n "$dir/_robotperf"
# shellcheck disable=SC1091
source "$dir/robotperf.bash"
complete_line() {  # the words `robotperf ARGS... <TAB>` is offered, the last ARG being typed
  COMP_WORDS=("$exe" "$@")
  COMP_CWORD=$(($# ))
  COMPREPLY=()
  _robotperf
  echo "${COMPREPLY[*]}"
}
failed=0
expect() {  # expect "WORDS OFFERED" ARGS...
  local want=$1
  shift
  local got
  got=$(complete_line "$@")
  if [[ " $got " != *" $want "* ]]; then
    echo "FAIL: robotperf $* <TAB> offered '$got', not '$want'" >&2
    failed=1
  fi
}
refuse() {  # refuse "WORD" ARGS...: WORD is not offered
  local got
  got=$(complete_line "${@:2}")
  if [[ " $got " == *" $1 "* ]]; then
    echo "FAIL: robotperf ${*:2} <TAB> offered '$1'" >&2
    failed=1
  fi
}
expect "describe" des
expect "results" res
expect "list" results li
expect "--rmw" run a1 --rm
expect "fastdds" run a1 --rmw ""
expect "cyclonedds" run a1 --rmw c
expect "a1" run a
expect "d6" describe d
expect "kernels" list k
expect "--ids" list --i
refuse "run" results ""
refuse "--rmw" describe --r
exit $failed
