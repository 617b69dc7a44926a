#!/bin/bash
# VM scenario with systemd as PID 1 (tests/vm/run-vm --systemd): the installed units of slamd, based,
# camerad and whiskerd run under a real service manager with every sandboxing setting they ship with,
# as on the robot. Per daemon: `systemctl start` returns once READY=1 came; the main process runs as
# whiskeye with no capabilities, no new privileges and its seccomp filter; its LCM traffic reaches a
# listener over udpm://; `systemctl stop` ends it cleanly. Also: based's watchdog really gets it killed
# and restarted by systemd when a worker thread stalls, and whiskerd's control thread gets SCHED_FIFO.
# The hardware-specific parts are replaced by drop-ins, as a user would: based talks to the fake
# Robotino server, whiskerd uses a vcan named can0 without GPIO, camerad the vivid test camera.
#   scenario_systemd_units.sh RESULTS_DIR STAGE FAKE_ROBOTINO_SERVER
# STAGE is a DESTDIR into which the project was installed with --prefix /opt/whiskeye, plus
# etc/whiskeye/whiskerd-vm.yaml (tests/vm/whiskerd_vm.yaml).
set -u
RESULTS_DIR=$1
STAGE=$2
FAKE_ROBOTINO=$3
source "$(dirname "$0")/../vm/lib.sh"
P=/opt/whiskeye
U=/run/systemd/system

if [ "$(cat /proc/1/comm)" != systemd ]; then
  fail systemd_is_pid1 "PID 1 is $(cat /proc/1/comm); run this scenario with run-vm --systemd"
  exit 0
fi
mkdir -p $P && mount --bind "$STAGE$P" $P

# The service user, as systemd-sysusers creates it from $P/lib/sysusers.d/whiskeye.conf (the host
# root is read-only here and the account files are writable copies, which sysusers cannot replace).
grep -q '^u whiskeye ' $P/lib/sysusers.d/whiskeye.conf || fail sysusers_file "no whiskeye user in it"
echo "whiskeye:x:990:990:WhiskEye onboard stack:/var/lib/whiskeye:/usr/sbin/nologin" >> /etc/passwd
echo "whiskeye:!*:19000::::::" >> /etc/shadow
echo "whiskeye:x:990:" >> /etc/group
# (`m whiskeye video`: written in place, the copy is a bind mount that sed -i could not replace.)
groups=$(sed 's/^\(video:x:[0-9]*:\)\(..*\)$/\1\2,whiskeye/; s/^\(video:x:[0-9]*:\)$/\1whiskeye/' /etc/group)
printf '%s\n' "$groups" > /etc/group
check service_user_exists_and_is_in_group_video bash -c 'id -nG whiskeye | grep -qw video || { id whiskeye; false; }'

sysctl -q -p $P/lib/sysctl.d/60-whiskeye-lcm.conf
setup_lcm_loopback
cp $P/lib/systemd/system/*.service $P/lib/systemd/system/*.target $U/

# Drop-ins for the hardware this VM does not have.
mkdir -p $U/based.service.d $U/whiskerd.service.d $U/whiskeye-can0.service.d
cat > $U/based.service.d/vm.conf <<EOF
[Service]
ExecStart=
ExecStart=$P/bin/based --config $P/etc/whiskeye/based.yaml --url http://127.0.0.1:18080
EOF
cat > $U/whiskeye-can0.service.d/vm.conf <<EOF
[Service]
ExecStart=
ExecStart=/usr/sbin/ip link set can0 mtu 72 up
EOF
cat > $U/whiskerd.service.d/vm.conf <<EOF
[Service]
ExecStart=
ExecStart=$P/bin/whiskerd --config $P/etc/whiskeye/whiskerd-vm.yaml -i can0 --no-gpio
EOF
systemctl daemon-reload

# Messages on CHANNEL received by a listener in SECONDS.
count_messages() {
  local log=$RESULTS_DIR/listen-$1.lcmlog
  rm -f "$log"
  timeout "$2" lcm-logger -q -f -c "$1" --lcm-url="$LCM_DEFAULT_URL" "$log" >/dev/null 2>&1
  grep -ao "$1" "$log" 2>/dev/null | wc -l
}
# The sandbox the kernel applied to a unit's main process, and its user.
sandboxed() {
  local pid
  pid=$(systemctl show -P MainPID "$1")
  [ "$pid" -gt 0 ] || { echo "$1 has no main process"; return 1; }
  local user
  user=$(ps -o user= -p "$pid" | tr -d ' ')
  [ "$user" = whiskeye ] || { echo "$1 runs as '$user'"; return 1; }
  grep -Eq '^NoNewPrivs:\s+1$' /proc/$pid/status || { echo "$1: NoNewPrivs not set"; return 1; }
  grep -Eq '^Seccomp:\s+2$' /proc/$pid/status || { echo "$1: no seccomp filter"; return 1; }
  grep -Eq '^CapEff:\s+0+$' /proc/$pid/status || { echo "$1: has capabilities $(grep CapEff /proc/$pid/status)"; return 1; }
  grep -Eq '^CapBnd:\s+0+$' /proc/$pid/status || { echo "$1: capability bounding set not empty"; return 1; }
}
active_for() {  # UNIT SECONDS: still active (not restarted) after that long
  local n0
  n0=$(systemctl show -P NRestarts "$1")
  sleep "$2"
  systemctl is-active -q "$1" && [ "$(systemctl show -P NRestarts "$1")" = "$n0" ]
}
stopped_cleanly() {
  systemctl stop "$1" || return 1
  local result status
  result=$(systemctl show -P Result "$1")
  status=$(systemctl show -P ExecMainStatus "$1")
  [ "$result" = success ] && [ "$status" = 0 ] || { echo "$1: Result=$result ExecMainStatus=$status"; return 1; }
}
journal() { journalctl -q -o cat -u "$1" --no-pager; }

# --- slamd ---
check slamd_starts_ready_under_systemd timeout 120 systemctl start slamd.service
check slamd_runs_as_whiskeye_sandboxed sandboxed slamd.service
check slamd_stays_up active_for slamd.service 5
n=$(count_messages SLAM_STATUS 5)
check slamd_publishes_slam_status_over_lcm test "$n" -ge 2
check slamd_state_directory_belongs_to_whiskeye \
  bash -c '[ "$(stat -c %U:%a /var/lib/slamd)" = whiskeye:750 ] || { stat -c %U:%a /var/lib/slamd; false; }'
check slamd_stops_cleanly stopped_cleanly slamd.service
check slamd_wrote_its_final_checkpoint bash -c 'ls /var/lib/slamd/checkpoint-*.vslam || { ls -la /var/lib/slamd; false; }'
# The next start resumes from it: the file is a checkpoint this slamd loads, in the sandbox.
resumes() {
  systemctl start slamd.service || return 1
  for _ in $(seq 60); do
    journal slamd.service | grep -q "resuming from /var/lib/slamd/checkpoint-" && return 0
    sleep 1
  done
  journal slamd.service | tail -n 5
  return 1
}
check slamd_resumes_from_its_checkpoint_on_the_next_start resumes
check slamd_stops_cleanly_again stopped_cleanly slamd.service
journal slamd.service > "$RESULTS_DIR/slamd.journal"

# --- based, against the fake Robotino server ---
"$FAKE_ROBOTINO" --port 18080 > "$RESULTS_DIR/fake-robotino.log" 2>&1 &
fake=$!
check based_starts_ready_under_systemd timeout 120 systemctl start based.service
check based_runs_as_whiskeye_sandboxed sandboxed based.service
check based_stays_up active_for based.service 5
n=$(count_messages ODOMETRY 4)
check based_publishes_odometry_over_lcm test "$n" -ge 20
# A stalled worker thread: no more keep-alives, so systemd kills based (SIGABRT) and restarts it.
cat > $U/based.service.d/stall.conf <<EOF
[Service]
Environment=WHISKEYE_FAULT_INJECT=stall-worker-after=3s
EOF
systemctl daemon-reload
systemctl restart based.service
restarted() {
  for _ in $(seq 60); do
    [ "$(systemctl show -P NRestarts based.service)" -ge 1 ] && return 0
    sleep 1
  done
  echo "NRestarts=$(systemctl show -P NRestarts based.service)"; journal based.service | tail -n 5; return 1
}
check based_watchdog_restarts_it_when_a_worker_thread_stalls restarted
check systemd_reported_the_watchdog_timeout bash -c "journalctl -q -o cat --no-pager | grep -q 'based.service: Watchdog timeout'"
rm $U/based.service.d/stall.conf
systemctl daemon-reload
systemctl restart based.service
check based_stops_cleanly stopped_cleanly based.service
journal based.service > "$RESULTS_DIR/based.journal"
kill "$fake"; wait "$fake"

# --- camerad, on the vivid test camera ---
modprobe vivid n_devs=1 node_types=0x1 input_types=0x1
udevadm settle -t 20 2>/dev/null || true
check camerad_starts_ready_under_systemd timeout 120 systemctl start camerad.service
check camerad_runs_as_whiskeye_sandboxed sandboxed camerad.service
check camerad_stays_up active_for camerad.service 5
n=$(count_messages CAMERA 8)
check camerad_publishes_camera_frames_over_lcm test "$n" -ge 2
check camerad_stops_cleanly stopped_cleanly camerad.service
journal camerad.service > "$RESULTS_DIR/camerad.journal"
# A misspelt key: exit status 2, which the unit does not restart on (RestartPreventExitStatus=2).
printf 'camera: {widht: 640}\n' > /run/camerad-bad.yaml
mkdir -p $U/camerad.service.d
cat > $U/camerad.service.d/bad.conf <<EOF
[Service]
ExecStart=
ExecStart=$P/bin/camerad --config /run/camerad-bad.yaml
EOF
systemctl daemon-reload
fails_once() {
  systemctl start camerad.service 2>/dev/null && { echo "camerad started with a bad config"; return 1; }
  sleep 4  # RestartSec=1s: a restart loop would have begun
  local restarts status
  restarts=$(systemctl show -P NRestarts camerad.service)
  status=$(systemctl show -P ExecMainStatus camerad.service)
  [ "$restarts" = 0 ] && [ "$status" = 2 ] && systemctl is-failed -q camerad.service &&
    journal camerad.service | grep -q "camerad: bad config: .*widht" ||
    { echo "NRestarts=$restarts ExecMainStatus=$status"; journal camerad.service | tail -n 3; return 1; }
}
check camerad_with_a_bad_config_fails_once_and_is_not_restarted fails_once
rm $U/camerad.service.d/bad.conf
systemctl daemon-reload
systemctl reset-failed camerad.service

# --- whiskerd, on a vcan named can0 (whiskeye-can0.service brings it up) ---
setup_vcan can0
check whiskerd_starts_ready_under_systemd timeout 120 systemctl start whiskerd.service
check whiskerd_runs_as_whiskeye_sandboxed sandboxed whiskerd.service
check whiskerd_stays_up active_for whiskerd.service 5
fifo() {
  ps -L -o cls=,rtprio= -p "$(systemctl show -P MainPID whiskerd.service)" | grep -Eq '^\s*FF\s+80$' ||
    { ps -L -o tid,cls,rtprio,comm -p "$(systemctl show -P MainPID whiskerd.service)"; false; }
}
check whiskerd_control_thread_runs_sched_fifo_80 fifo
n=$(count_messages DRIVER_STATUS 4)
check whiskerd_publishes_driver_status_over_lcm test "$n" -ge 2
check whiskerd_stops_cleanly stopped_cleanly whiskerd.service
journal whiskerd.service > "$RESULTS_DIR/whiskerd.journal"
journal whiskeye-can0.service > "$RESULTS_DIR/whiskeye-can0.journal"
exit 0
