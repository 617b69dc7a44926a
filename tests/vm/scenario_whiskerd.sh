#!/bin/bash
# VM scenario: whiskerd on vcan0 (FD MTU) against the board emulator, in CAN FD mode then in
# classic mode; LCM over loopback multicast.
#   scenario_whiskerd.sh RESULTS_DIR WHISKERD WHISKER_VM_CHECK CONFIG DRIVER_STATUS_PROBE
set -u
RESULTS_DIR=$1
WHISKERD=$2
CHECK=$3
CONFIG=$4
PROBE=$5
source "$(dirname "$0")/lib.sh"

setup_lcm_loopback
setup_vcan vcan0

# run_mode MODE CONFIG PREFIX: candump records the motor commands on the wire (independently of the
# checker's own decoding) in /tmp/motor_MODE.log; whiskerd runs until the checker is done, then
# gets SIGTERM.
run_mode() {
  local mode=$1 config=$2 prefix=$3
  candump -L vcan0,200:7F8 > "/tmp/motor_$mode.log" 2>&1 &
  local dump_pid=$!
  "$WHISKERD" -c "$config" --no-gpio > "$RESULTS_DIR/whiskerd_$mode.log" 2>&1 &
  local wd_pid=$!
  local check_rc=0
  "$CHECK" --mode "$mode" --interface vcan0 --results "$RESULTS_DIR/results.txt" > "$RESULTS_DIR/check_$mode.log" 2>&1 \
    || check_rc=$?
  cat "$RESULTS_DIR/check_$mode.log"
  exited_ok "${prefix}whisker_vm_check_exits_0" "$check_rc"
  kill -TERM $wd_pid
  wait $wd_pid
  local rc=$?
  kill $dump_pid 2>/dev/null
  check "${prefix}whiskerd_exits_cleanly_on_sigterm" test "$rc" = 0
  check "${prefix}whiskerd_reports_motors_disabled_at_exit" grep -q 'stopped, motors disabled' "$RESULTS_DIR/whiskerd_$mode.log"
  cp "/tmp/motor_$mode.log" "$RESULTS_DIR/" 2>/dev/null
}

run_mode fd "$CONFIG" ""
# Where frames could be dropped silently (second column of softnet_stat: backlog drops).
cat /proc/net/softnet_stat
ip -s link show vcan0
# FD frames of 64 bytes on 0x200 (candump prints 128 hex digits after ##<flags>).
check candump_sees_64_byte_fd_motor_frames grep -Eq 'vcan0 200##[0-9A-F][0-9A-F]{128}$' /tmp/motor_fd.log
# The last command on the wire has the enable mask (bytes 2..4) cleared.
check last_motor_frame_on_the_wire_is_disabled \
  bash -c "tail -n 1 /tmp/motor_fd.log | grep -Eq 'vcan0 200##[0-9A-F][0-9A-F]{4}000000'"

# The same script on classic CAN (100 Hz, one frame per whisker, per-board commands).
sed 's/^can:$/can:\n  mode: classic/' "$CONFIG" > /tmp/whiskerd_classic.yaml
run_mode classic /tmp/whiskerd_classic.yaml classic_
check classic_whiskerd_runs_classic_can_at_100_hz grep -q "vcan0 (classic CAN, 100 Hz)" "$RESULTS_DIR/whiskerd_classic.log"
check candump_sees_8_byte_classic_motor_frames_per_board \
  bash -c "for id in 201 202 203 204 205 206; do grep -Eq \"vcan0 \$id#[0-9A-F]{16}\$\" /tmp/motor_classic.log || exit 1; done"
# Every board's last classic command disables all four whiskers (0x8000 = disabled).
check classic_last_motor_frames_are_disabled \
  bash -c "for id in 201 202 203 204 205 206; do grep \"vcan0 \$id#\" /tmp/motor_classic.log | tail -n 1 | grep -q '#0080008000800080' || exit 1; done"

# can::Socket alone: the interface going down is reported by the next receive even when a send took
# the kernel's one report of it (the race that whiskerd_notices_the_interface_going_down can lose).
socket_rc=0
"$CHECK" --socket-down --interface vcan0 --results "$RESULTS_DIR/results.txt" > "$RESULTS_DIR/check_socket_down.log" 2>&1 \
  || socket_rc=$?
cat "$RESULTS_DIR/check_socket_down.log"
exited_ok socket_down_check_exits_0 "$socket_rc"
ip link set vcan0 up

# The CAN interface going away under whiskerd: taken down and up (an adapter reset), then deleted
# and created again (a USB adapter unplugged and plugged back). whiskerd reopens it, with backoff
# while it does not exist, and receives frames again; it never exits.
log=$RESULTS_DIR/whiskerd_reopen.log
"$WHISKERD" -c "$CONFIG" --no-gpio > "$log" 2>&1 &
wd=$!
wait_for "$log" "vcan0 (CAN FD" 60 || echo "whiskerd did not start"
# heartbeats N: N well-formed heartbeat frames from board 1 (2 bytes: NMT operational, no status
# bits); they do not feed control, and are counted as received frames and as heartbeats.
heartbeats() { for _ in $(seq "$1"); do cansend vcan0 701#0500; sleep 0.01; done; }
ip link set vcan0 down
check whiskerd_notices_the_interface_going_down wait_for "$log" "reopening" 20
# Reopened while still down, the socket waits for the interface; it must not report itself down again
# and again (the first receive after a reopen taking can-raw's pending ENETDOWN: a reopen every period).
sleep 2
check whiskerd_does_not_reopen_again_and_again_while_the_interface_is_down \
  bash -c "n=\$(grep -c 'reopening' '$log'); echo \"\$n reopenings\"; [ \"\$n\" -le 2 ]"
ip link set vcan0 up
heartbeats 20
"$PROBE" --driver whiskerd --seconds 3 > /tmp/status_up.txt
cat /tmp/status_up.txt
check whiskerd_receives_again_after_down_and_up \
  bash -c "grep -Eq '^can_reopens=[1-9]' /tmp/status_up.txt && grep -Eq '^can_rx_frames=([2-9][0-9]|[1-9][0-9]{2,})$' /tmp/status_up.txt && grep -Eq '^heartbeats=([2-9][0-9]|[1-9][0-9]{2,})$' /tmp/status_up.txt"
ip link del vcan0
check whiskerd_says_it_retries_while_the_interface_does_not_exist \
  wait_for "$log" "CAN vcan0: no such interface: No such device; retrying" 20
sleep 2  # whiskerd retries with backoff while vcan0 does not exist
setup_vcan vcan0
# The earlier down/up reopened it too: only a "reopened" after the "retrying" counts.
check whiskerd_reopens_a_recreated_interface \
  bash -c "for _ in \$(seq 300); do sed -n '/; retrying/,\$p' '$log' | grep -q 'CAN vcan0 reopened' && exit 0; sleep 0.1; done; exit 1"
heartbeats 20
"$PROBE" --driver whiskerd --seconds 3 > /tmp/status_new.txt
cat /tmp/status_new.txt
check whiskerd_receives_on_the_recreated_interface \
  bash -c "grep -Eq '^can_rx_frames=([4-9][0-9]|[1-9][0-9]{2,})$' /tmp/status_new.txt"
# A frame of the wrong length: counted, and the log names what was wrong (the 1st, 10th, 100th, ...).
cansend vcan0 181##00011223344556677
check whiskerd_logs_what_was_wrong_with_a_rejected_frame \
  wait_for "$log" "rejected frame: .*(8 bytes, expected 32), id 0x181" 20
check whiskerd_survives_its_interface_going_away kill -0 $wd
kill -TERM $wd
wait $wd
check whiskerd_exits_cleanly_after_losing_its_interface test $? = 0
cat "$log"
exit 0
