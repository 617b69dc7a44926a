#!/usr/bin/env bash
# cmake/WhiskeyeVersion.cmake in a source tree without .git (a tarball), here unpacked in the build
# tree (inside the git checkout when the build is): --version's text is the project version alone,
# not the enclosing repository's description.
#   version_without_git.sh SOURCE_DIR SCRATCH_DIR
set -euo pipefail
src=$1
tmp=$(mktemp -d "$2/version-test.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/tree"
cmake -DSOURCE_DIR="$tmp/tree" -DVERSION=9.8.7 -DTEMPLATE="$src/common/src/version.cpp.in" \
      -DOUTPUT="$tmp/version.cpp" -P "$src/cmake/WhiskeyeVersion.cmake"
grep -q 'return "9.8.7";' "$tmp/version.cpp" || { cat "$tmp/version.cpp"; echo "not the project version alone" >&2; exit 1; }
# And from the checkout itself: the git description in brackets.
cmake -DSOURCE_DIR="$src" -DVERSION=9.8.7 -DTEMPLATE="$src/common/src/version.cpp.in" \
      -DOUTPUT="$tmp/version.cpp" -P "$src/cmake/WhiskeyeVersion.cmake"
if [ -e "$src/.git" ]; then
  grep -Eq 'return "9\.8\.7 \([0-9a-zA-Z.+_-]+\)";' "$tmp/version.cpp" || { cat "$tmp/version.cpp"; echo "no git description" >&2; exit 1; }
fi
echo ok
