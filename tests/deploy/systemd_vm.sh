#!/bin/bash
# Host side of the deploy.systemd_units VM test: installs the project into a staging DESTDIR with the
# prefix /opt/whiskeye (the guest bind-mounts it there, so the units' absolute paths hold), then boots
# the VM with systemd as PID 1 and runs scenario_systemd_units.sh in it.
#   systemd_vm.sh BUILD_DIR WORK_DIR FAKE_ROBOTINO_SERVER WHISKERD_VM_YAML
set -euo pipefail
build=$1
work=$2
here=$(cd "$(dirname "$0")" && pwd)
stage=$(realpath -m "$work-stage")
rm -rf "$stage"
DESTDIR="$stage" cmake --install "$build" --prefix /opt/whiskeye >/dev/null
# whiskerd's VM config goes into the staged config folder: a checkout under /tmp would be hidden from
# the service by its PrivateTmp=yes.
cp "$4" "$stage/opt/whiskeye/etc/whiskeye/whiskerd-vm.yaml"
exec "$here/../vm/run-vm" --systemd "$work" "$here/scenario_systemd_units.sh" 420 "$stage" "$3"
