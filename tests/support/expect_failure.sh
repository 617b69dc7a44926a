#!/usr/bin/env bash
# expect_failure.sh STATUS PATTERN COMMAND [ARGS...]: passes when COMMAND exits with STATUS and its
# output (stdout and stderr) has a line matching the extended regex PATTERN. For ctest tests of a
# tool's bad-input path: ctest's PASS_REGULAR_EXPRESSION alone ignores the exit status.
set -u
want=$1 pattern=$2
shift 2
out=$("$@" 2>&1)
status=$?
echo "$out"
if [ "$status" != "$want" ]; then
  echo "expect_failure: exit status $status, expected $want" >&2
  exit 1
fi
if ! grep -Eq -- "$pattern" <<<"$out"; then
  echo "expect_failure: no line matches '$pattern'" >&2
  exit 1
fi
