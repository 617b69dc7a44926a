#!/bin/bash
# Host side of vm.deb_lifecycle: builds the .deb twice with cpack (the build's version, then the same
# tree as a higher Debian revision, the upgrade), runs lintian on the first and fails on any error
# (E:) line, then boots the VM with systemd as PID 1 (tests/vm/run-vm --systemd) and runs
# scenario_deb.sh there: dpkg -i, start whiskeye.target, upgrade, dpkg -r, dpkg -P.
#   deb_vm.sh BUILD_DIR WORK_DIR FAKE_ROBOTINO_SERVER WHISKERD_VM_YAML
set -euo pipefail
build=$1
work=$(realpath -m "$2")
here=$(cd "$(dirname "$0")" && pwd)
debs=$(realpath -m "$work-debs")
rm -rf "$debs"
mkdir -p "$debs/1" "$debs/2"
start=$(date +%s)
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$debs/1" >"$debs/cpack-1.log" 2>&1 ||
  { echo "deb_vm: cpack failed:" >&2; tail -n 20 "$debs/cpack-1.log" >&2; exit 1; }
deb1=$(ls "$debs"/1/whiskeye_*.deb)
version=$(dpkg-deb -f "$deb1" Version)
# The upgrade: the same tree packaged as a higher revision (0.1.0-1 -> 0.1.0-1+vmupgrade1).
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$debs/2" -D "CPACK_DEBIAN_PACKAGE_RELEASE=${version#*-}+vmupgrade1" \
  >"$debs/cpack-2.log" 2>&1 || { echo "deb_vm: cpack (upgrade) failed:" >&2; tail -n 20 "$debs/cpack-2.log" >&2; exit 1; }
deb2=$(ls "$debs"/2/whiskeye_*.deb)
if ! dpkg --compare-versions "$(dpkg-deb -f "$deb2" Version)" gt "$version"; then
  echo "deb_vm: the upgrade package's version $(dpkg-deb -f "$deb2" Version) is not above $version" >&2
  exit 1
fi
echo "deb_vm: built $(basename "$deb1") and $(basename "$deb2") in $(( $(date +%s) - start ))s" >&2

# lintian: no error (its exit status with --fail-on error, and no E: line); the warnings are the ones
# docs/deployment.md lists and justifies.
set +e
lintian --fail-on error --no-tag-display-limit "$deb1" >"$debs/lintian.txt" 2>&1
lintian_rc=$?
set -e
sed 's/^/  lintian| /' "$debs/lintian.txt" >&2
if [ "$lintian_rc" != 0 ] || grep -q '^E: ' "$debs/lintian.txt"; then
  echo "deb_vm: lintian exited $lintian_rc or reports errors on $(basename "$deb1")" >&2
  exit 1
fi
echo "deb_vm: lintian: no errors, $(grep -c '^W: ' "$debs/lintian.txt" || true) warning(s)" >&2

# dpkg's database for the guest: the status of the packages the .deb depends on, as installed here, and
# nothing else. dpkg -i checks the Depends against it exactly as on the robot; the host's whole
# database (~190,000 files) would cost each dpkg run in the TCG guest a minute of reading.
db="$debs/dpkg-db"
mkdir -p "$db/info" "$db/updates" "$db/triggers"
: > "$db/available"
: > "$db/status"
for deb in "$deb1" "$deb2"; do dpkg-deb -f "$deb" Pre-Depends Depends; done | sed 's/^[A-Za-z-]*://' | tr ',|' '\n\n' |
  sed 's/([^)]*)//; s/:any//; s/ //g' | grep -v '^$' | sort -u | while read -r p; do
  if dpkg-query -s "$p" >/dev/null 2>&1; then
    dpkg-query -s "$p" | grep -v '^Conffiles:\|^ /' >> "$db/status"
    echo >> "$db/status"
    : > "$db/info/$(dpkg-query -W -f='${binary:Package}' "$p").list"
  fi
done

# The guest's limit catches a hang, not slowness: the scenario takes 190-430 s on an idle or lightly
# loaded host, but a TCG guest slows down 5x and more when the host's two cores are busy: 600 s cut
# it off at load average 5-7 (dpkg -P), and 1200 s at load 3-3.6 beside a sanitizer build, where
# each Perl helper of the upgrade's postinst took 10-40 s (2026-12-05).
exec "$here/../vm/run-vm" --systemd "$work" "$here/scenario_deb.sh" 2400 "$deb1" "$deb2" "$3" "$4" "$db"
