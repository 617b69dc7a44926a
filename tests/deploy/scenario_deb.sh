#!/bin/bash
# VM scenario with systemd as PID 1 (tests/vm/run-vm --systemd): the .deb's life on a Debian system.
# dpkg -i (the postinst creates the user), then starting whiskeye.target brings every daemon up; a
# daemon's warning reaches the journal with its priority; dpkg -i of a higher version restarts the
# running daemons (new MainPID and ActiveEnterTimestamp) and keeps slamd's state and the operator's
# edit of a conffile; dpkg -r stops every unit and keeps the conffiles; dpkg -P removes them and the
# state. The hardware is replaced by drop-ins in /run, as in scenario_systemd_units.sh.
#   scenario_deb.sh RESULTS_DIR DEB DEB_UPGRADE FAKE_ROBOTINO_SERVER WHISKERD_VM_YAML DPKG_DB
# The guest's root is the host's, read-only: /usr and /etc become overlays with a tmpfs upper layer,
# so dpkg installs for real and the host is untouched. DPKG_DB (deb_vm.sh) is dpkg's database with
# the status of the packages the .deb depends on, copied to the guest's /var/lib/dpkg (a tmpfs).
set -u
RESULTS_DIR=$1
DEB=$2
DEB_UPGRADE=$3
FAKE_ROBOTINO=$4
WHISKERD_VM_YAML=$5
DPKG_DB=$6
source "$(dirname "$0")/../vm/lib.sh"
U=/run/systemd/system
DAEMONS="whiskerd camerad based slamd"
UNITS="whiskeye.target whiskeye-can0.service whiskerd.service camerad.service based.service slamd.service"

if [ "$(cat /proc/1/comm)" != systemd ]; then
  fail systemd_is_pid1 "PID 1 is $(cat /proc/1/comm); run this scenario with run-vm --systemd"
  exit 0
fi
mkdir -p /run/vm-debs && cp "$DEB" "$DEB_UPGRADE" /run/vm-debs/ && cp "$WHISKERD_VM_YAML" /run/vm-debs/whiskerd-vm.yaml
DEB=/run/vm-debs/$(basename "$DEB")
DEB_UPGRADE=/run/vm-debs/$(basename "$DEB_UPGRADE")
overlay() {  # LOWER MOUNTPOINT
  local d
  d=/run/overlay/$(echo "$2" | tr / _)
  mkdir -p "$d/upper" "$d/work" "$2"
  mount -t overlay overlay -o "lowerdir=$1,upperdir=$d/upper,workdir=$d/work" "$2"
}
overlay /usr /usr && overlay /etc /etc || { fail writable_system "cannot overlay /usr or /etc"; exit 0; }
mkdir -p /var/log /var/cache /var/lib
cp -a "$DPKG_DB" /var/lib/dpkg
# The host is a container image whose policy-rc.d (exit 101) forbids every service start or restart
# from maintainer scripts; a robot has none, and the upgrade's restart is under test.
rm -f /usr/sbin/policy-rc.d

setup_lcm_loopback
setup_vcan can0
modprobe vivid n_devs=1 node_types=0x1 input_types=0x1
udevadm settle -t 20 2>/dev/null || true
"$FAKE_ROBOTINO" --port 18080 > "$RESULTS_DIR/fake-robotino.log" 2>&1 &
fake=$!
# What the maintainer scripts run, every 5 s (a slow or stuck step shows in the results folder).
(while sleep 5; do
  echo "--- $SECONDS s"; ps -eo pid,etime,args | grep -E "deb-systemd|systemctl|postinst|prerm|postrm|sysusers|udevadm" | grep -v grep
done) > "$RESULTS_DIR/maintainer-scripts-ps.txt" 2>&1 &
watcher=$!

# dpkg succeeds within 900 s: a hang, not a slow guest (the upgrade's postinst took over 300 s in a
# TCG guest on a busy host; deb_vm.sh).
dpkg_ok() {  # LOG DPKG_ARGS...: dpkg succeeds in time; its output in the results folder
  local log=$RESULTS_DIR/$1 t=$SECONDS
  shift
  if ! timeout 900 dpkg "$@" > "$log" 2>&1; then
    tail -n 5 "$log"
    systemctl list-jobs --no-pager | head -n 10
    ps -eo pid,etime,args | grep -E "deb-systemd|systemctl|dpkg" | grep -v grep
    return 1
  fi
  echo "dpkg $*: $((SECONDS - t)) s" >> "$RESULTS_DIR/timing.txt"
}
status_is() { [ "$(dpkg-query -W -f='${Status}' whiskeye 2>/dev/null)" = "$1" ]; }

# --- install ---
check dpkg_installs_the_package dpkg_ok dpkg-install.log -i "$DEB"
check package_is_installed status_is "install ok installed"
check postinst_created_the_service_user_in_group_video bash -c 'id -nG whiskeye | grep -qw video || { id whiskeye; false; }'
check postinst_applied_the_lcm_sysctl bash -c '[ "$(sysctl -n net.core.rmem_max)" -ge 8388608 ]'
check package_enables_nothing bash -c '! systemctl -q is-enabled whiskeye.target slamd.service'
check units_run_the_packaged_binaries bash -c 'systemctl cat slamd.service | grep -q "^ExecStart=/usr/bin/slamd "'
check man_pages_are_installed bash -c 'man -w 8 slamd | grep -qx /usr/share/man/man8/slamd.8.gz &&
  man -w 8 whiskerd | grep -qx /usr/share/man/man8/whiskerd.8.gz && man -w 1 vita-sim | grep -qx /usr/share/man/man1/vita-sim.1.gz'

# Drop-ins for the hardware this VM does not have.
mkdir -p $U/based.service.d $U/whiskerd.service.d $U/whiskeye-can0.service.d
printf '[Service]\nExecStart=\nExecStart=/usr/bin/based --config /etc/whiskeye/based.yaml --url http://127.0.0.1:18080\n' \
  > $U/based.service.d/vm.conf
printf '[Service]\nExecStart=\nExecStart=/usr/sbin/ip link set can0 mtu 72 up\n' > $U/whiskeye-can0.service.d/vm.conf
printf '[Service]\nExecStart=\nExecStart=/usr/bin/whiskerd --config /run/vm-debs/whiskerd-vm.yaml -i can0 --no-gpio\n' \
  > $U/whiskerd.service.d/vm.conf
systemctl daemon-reload

all_active() {  # SECONDS: every unit of the target active within them
  local u
  for _ in $(seq "$1"); do
    for u in $UNITS; do
      systemctl -q is-active "$u" || { sleep 1; continue 2; }
    done
    return 0
  done
  for u in $UNITS; do echo "$u: $(systemctl is-active "$u")"; done
  return 1
}
systemctl start whiskeye.target
check whiskeye_target_starts_every_unit all_active 120
check slamd_runs_as_whiskeye bash -c '[ "$(ps -o user= -p "$(systemctl show -P MainPID slamd.service)" | tr -d " ")" = whiskeye ]'

# --- journal priorities: a warning is a warning, an info line is not ---
# An undecodable WHISK_CYCLE (LCM's short-message datagram: magic, sequence, channel, payload): slamd
# logs "WHISK_CYCLE: cannot decode ..." as a warning (common/log.h).
python3 - <<'PY'
import socket, struct
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
s.sendto(struct.pack(">II", 0x4C433032, 1) + b"WHISK_CYCLE\0" + b"not a whisk cycle", ("239.255.76.67", 7667))
PY
slamd_journal() { journalctl -q --no-pager -u slamd.service "$@"; }
warning_has_its_priority() {
  local w=
  for _ in $(seq 30); do
    w=$(slamd_journal -o cat -p warning)
    echo "$w" | grep -q "slamd: WHISK_CYCLE: cannot decode" && break
    sleep 1
  done
  echo "$w" | grep -q "slamd: WHISK_CYCLE: cannot decode" ||
    { echo "not at warning: $(slamd_journal -o cat | tail -n 3)"; return 1; }
  # The info line is in the journal, at info, and not among the warnings.
  slamd_journal -o cat -p info | grep -q "slamd: running in" || { echo "no info line at all"; return 1; }
  ! echo "$w" | grep -q "slamd: running in" || { echo "an info line shows at -p warning"; return 1; }
  # Stored as PRIORITY=4, without the "<4>" prefix.
  slamd_journal -o json | grep "WHISK_CYCLE: cannot decode" | grep -q '"PRIORITY":"4"' || { echo "not PRIORITY=4"; return 1; }
  ! slamd_journal -o cat | grep -q "^<[0-9]>" || { echo "a raw <N> prefix in the journal"; return 1; }
}
check journal_shows_slamds_warning_at_priority_warning_and_not_its_info_lines warning_has_its_priority

# --- upgrade: the running daemons restart on the new binaries; state and conffile edits stay ---
declare -A pid0 t0
for d in $DAEMONS; do
  pid0[$d]=$(systemctl show -P MainPID "$d.service")
  t0[$d]=$(systemctl show -P ActiveEnterTimestampMonotonic "$d.service")
done
echo "# edited by the operator" >> /etc/whiskeye/slam.yaml
echo "vm marker" > /var/lib/slamd/operator-note
check dpkg_upgrades_to_the_higher_version dpkg_ok dpkg-upgrade.log -i "$DEB_UPGRADE"
check upgraded_version_is_installed bash -c "[ \"\$(dpkg-query -W -f='\${Version}' whiskeye)\" = \"\$(dpkg-deb -f '$DEB_UPGRADE' Version)\" ]"
restarted() {
  local d p t bad=0
  all_active 60 || return 1
  for d in $DAEMONS; do
    p=$(systemctl show -P MainPID "$d.service")
    t=$(systemctl show -P ActiveEnterTimestampMonotonic "$d.service")
    if [ "$p" = "${pid0[$d]}" ] || [ "$t" = "${t0[$d]}" ] || [ "$p" = 0 ]; then
      echo "$d: MainPID ${pid0[$d]} -> $p, ActiveEnterTimestampMonotonic ${t0[$d]} -> $t"
      bad=1
    fi
  done
  return $bad
}
check upgrade_restarted_every_daemon restarted
check upgrade_kept_the_conffile_edit grep -q "^# edited by the operator" /etc/whiskeye/slam.yaml
check upgrade_kept_slamds_state bash -c 'grep -qx "vm marker" /var/lib/slamd/operator-note && ls /var/lib/slamd/checkpoint-*.vslam'
resumed() {
  for _ in $(seq 60); do
    slamd_journal -o cat | grep -q "resuming from /var/lib/slamd/checkpoint-" && return 0
    sleep 1
  done
  slamd_journal -o cat | tail -n 5
  return 1
}
check upgraded_slamd_resumes_from_its_checkpoint resumed

# --- remove: every unit stops, the conffiles stay ---
check dpkg_removes_the_package dpkg_ok dpkg-remove.log -r whiskeye
stopped() {
  local u d bad=0
  for u in $UNITS; do
    if systemctl -q is-active "$u"; then echo "$u still active"; bad=1; fi
  done
  for d in $DAEMONS; do
    if pgrep -x "$d" >/dev/null; then echo "$d still runs"; bad=1; fi
  done
  return $bad
}
check remove_stopped_every_unit stopped
check remove_removed_the_binaries_and_units bash -c '[ ! -e /usr/bin/slamd ] && [ ! -e /usr/lib/systemd/system/slamd.service ]'
check remove_kept_the_conffiles bash -c 'grep -q "^# edited by the operator" /etc/whiskeye/slam.yaml && [ -f /etc/default/whiskeye ]'
check package_is_config_files_only status_is "deinstall ok config-files"

# --- purge: configuration and state go ---
check dpkg_purges_the_package dpkg_ok dpkg-purge.log -P whiskeye
check purge_removed_the_configuration bash -c '[ ! -e /etc/whiskeye ] && [ ! -e /etc/default/whiskeye ] || { ls -la /etc/whiskeye /etc/default/whiskeye; false; }'
check purge_removed_the_state bash -c '[ ! -e /var/lib/slamd ] || { ls -la /var/lib/slamd; false; }'
purged() {
  local st
  st=$(dpkg-query -W -f='${Status}' whiskeye 2>/dev/null)
  case "$st" in ''|*" not-installed") return 0 ;; *) echo "status: $st"; return 1 ;; esac
}
check purge_left_no_package_record purged

for u in $UNITS; do journalctl -q -o short-monotonic --no-pager -u "$u" > "$RESULTS_DIR/${u%.*}.journal"; done
kill "$fake" "$watcher" 2>/dev/null
wait "$fake" "$watcher" 2>/dev/null
exit 0
