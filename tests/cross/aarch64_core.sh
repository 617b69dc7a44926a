#!/usr/bin/env bash
# The core's portable part built for aarch64 (Debian's cross compiler) and its unit tests run under
# qemu-user: the matcher (SAD, template store; on aarch64 the plain C++ SAD, which GCC vectorises
# for NEON), pose cells, experience map, tactile templates, and their test files. What it leaves out
# links libraries that have no arm64 copy on an amd64 machine without `dpkg --add-architecture
# arm64`: OpenCV (visual templates and so VitaSlam) and yaml-cpp (the parameter loaders: the
# linker's --gc-sections drops them, as these tests do not call them). docs/performance.md, "aarch64".
#   tests/cross/aarch64_core.sh SOURCE_DIR WORK_DIR
# Exit 0 when every test passes on aarch64, 1 when a build or a test fails; one line and exit 2 on a
# bad command line or a missing tool (scripts/install-deps installs them).
set -euo pipefail
if [ $# -ne 2 ]; then echo "aarch64_core.sh: needs SOURCE_DIR WORK_DIR" >&2; exit 2; fi
src=$1
work=$2
for tool in aarch64-linux-gnu-g++ qemu-aarch64-static; do
  if ! command -v "$tool" >/dev/null; then echo "aarch64_core.sh: $tool is missing (scripts/install-deps)" >&2; exit 2; fi
done
gtest=/usr/src/googletest/googletest
if [ ! -f "$gtest/src/gtest-all.cc" ]; then echo "aarch64_core.sh: no $gtest (libgtest-dev)" >&2; exit 2; fi
mkdir -p "$work"
cxx=(aarch64-linux-gnu-g++ -std=c++20 -Wall -Wextra -Werror -ffunction-sections -fdata-sections
     -I"$src/slamd/core/include" -I"$src/slamd/core/src" -I"$src/common/include" -I"$gtest/include"
     -I/usr/include/eigen3)
# The flags slamd/core/CMakeLists.txt gives the core (-ffp-contract=off matters more here: GCC
# contracts to fused multiply-adds by default on aarch64, which the matcher's exact bound forbids).
core=(-O3 -fno-math-errno -fno-trapping-math -ffp-contract=off)
objects=()
compile() {  # compile OUT SRC FLAGS...: in the background, at most two at a time
  local out=$1 in=$2
  shift 2
  objects+=("$out")
  "${cxx[@]}" "$@" -c "$in" -o "$out" &
  if [ "$(jobs -rp | wc -l)" -ge 2 ]; then wait -n; fi
}
compile "$work/gtest-all.o" "$gtest/src/gtest-all.cc" -O2 -I"$gtest" -Wno-error
compile "$work/gtest_main.o" "$gtest/src/gtest_main.cc" -O2
for f in sad template_store types pose_cells experience_map tactile_template; do
  compile "$work/core_$f.o" "$src/slamd/core/src/$f.cpp" "${core[@]}"
done
compile "$work/robot_geometry.o" "$src/common/src/robot_geometry.cpp" "${core[@]}"
# The tests' plain references (the pose cells' full-grid dynamics) must round as the core does: no
# fused multiply-adds either.
for t in sad template_store row_store binary_io pose_cells experience_map tactile_template; do
  compile "$work/test_$t.o" "$src/tests/slamd_core/test_$t.cpp" -O2 -ffp-contract=off
done
while [ "$(jobs -rp | wc -l)" -gt 0 ]; do wait -n; done
aarch64-linux-gnu-g++ -Wl,--gc-sections "${objects[@]}" -o "$work/core-tests-aarch64" -pthread
file -b "$work/core-tests-aarch64" | grep -q "ARM aarch64" || { echo "aarch64_core.sh: not an aarch64 binary" >&2; exit 1; }
exec qemu-aarch64-static -L /usr/aarch64-linux-gnu "$work/core-tests-aarch64"
