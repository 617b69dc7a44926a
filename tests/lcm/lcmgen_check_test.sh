#!/usr/bin/env bash
# The code generation step fails the build on a broken .lcm file, and also when lcm-gen exits 0
# without writing what was expected (it does so for some bad flags).
#   lcmgen_check_test.sh SOURCE_DIR
set -u
src="$1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
run() {  # run_lcmgen.cmake with FLAGS, INPUT, EXPECTED
  cmake -DLCM_GEN="$(command -v lcm-gen)" "-DFLAGS=$1" -DOUT_DIR="$work/out" "-DINPUTS=$2" "-DEXPECTED=$3" \
        -P "$src/cmake/run_lcmgen.cmake" >"$work/log" 2>&1
}
fail=0
cat >"$work/good.lcm" <<'LCM'
package whiskeye;
struct good_t { int64_t utime; double x; }
LCM
cat >"$work/broken.lcm" <<'LCM'
package whiskeye;
struct broken_t { int64_t utime double x; }
LCM
if ! run "-x;--cpp-hpath;$work/out" "$work/good.lcm" "$work/out/whiskeye/good_t.hpp"; then
  echo "FAIL: a valid file was rejected"; cat "$work/log"; fail=1
fi
if run "-x;--cpp-hpath;$work/out" "$work/broken.lcm" "$work/out/whiskeye/broken_t.hpp"; then
  echo "FAIL: a broken .lcm file was accepted"; fail=1
elif ! grep -q "lcm-gen failed\|did not write" "$work/log"; then
  echo "FAIL: no clear reason given"; cat "$work/log"; fail=1
fi
# An unknown flag: lcm-gen prints usage; nothing is generated, so the check must fail.
if run "--no-such-flag" "$work/good.lcm" "$work/out/whiskeye/good_t.hpp"; then
  echo "FAIL: an lcm-gen run that wrote nothing was accepted"; fail=1
fi
[ $fail = 0 ] && echo "PASS"
exit $fail
