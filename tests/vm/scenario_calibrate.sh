#!/bin/bash
# VM scenario: the first day with a robot on a real (v)CAN bus. The bring-up sessions of a simulated
# robot (calibrate_inputs.sh, a host fixture, in INPUTS) are played with can-utils' canplayer onto
# vcan0 (mapping vcan0=can0) while whiskeye-calibrate listens on the socket (bus, rest) or candump
# records them (taps, jig, sweep: map and gain are interactive live, theta reads a recorded sweep);
# theta sweeps live through whiskerd's control loop against closed-loop simulated boards
# (board_sim_vm); the drop-ins the tool writes must hold the true calibration (calibrate_vm_check),
# a silent board must fail the bus check and a fault during the sweep must stop it.
#   scenario_calibrate.sh RESULTS_DIR CALIBRATE CHECK INPUTS BOARDS
set -u
RESULTS_DIR=$1
CALIBRATE=$2
CHECK=$3
IN=$4
BOARDS=$5
source "$(dirname "$0")/lib.sh"

setup_vcan vcan0
sysctl -qw net.core.rmem_max=16777216   # candump's and the tool's 4-8 MB receive buffers
ETC=$RESULTS_DIR/etc
rm -rf "$ETC" && cp -r "$IN/etc" "$ETC"
ORDER=$(cat "$IN/order")
C=("$CALIBRATE" -c "$ETC/whiskerd.yaml")

# listen SECONDS LOG SUBCOMMAND ARGS...: the tool on the bus while LOG is played onto it.
listen() {
  local seconds=$1 log=$2
  shift 2
  "${C[@]}" "$@" -i vcan0 --seconds "$seconds" > "$RESULTS_DIR/$1.out" 2> "$RESULTS_DIR/$1.err" &
  local pid=$!
  wait_for "$RESULTS_DIR/$1.err" "listening on vcan0" || echo "the tool did not start"
  canplayer -I "$log" vcan0=can0
  local rc=0
  wait $pid || rc=$?
  cat "$RESULTS_DIR/$1.out" "$RESULTS_DIR/$1.err"
  return $rc
}
# record LOG OUT: candump's log of LOG played onto vcan0, written to the guest's tmpfs first (a
# slow write over 9p stalls candump until its socket overflows) with a receive buffer of 8 MB; every
# frame of LOG must be in it.
record() {
  local tmp=/tmp/$(basename "$2")
  candump -r 8388608 -L vcan0 > "$tmp" &
  local pid=$!
  sleep 0.5
  canplayer -I "$1" vcan0=can0
  sleep 1
  kill -INT $pid
  wait $pid
  cp "$tmp" "$2"
  local played recorded
  played=$(grep -c . "$1")
  recorded=$(grep -c . "$2")
  [ "$played" = "$recorded" ] || { echo "recorded $recorded of $played frames"; return 1; }
}

for f in rest.log taps.log jig.log sweep.log silent.log truth.yaml order; do
  check "input_${f//./_}_present" test -s "$IN/$f"
done
check bus_check_passes_on_the_live_bus listen 5 "$IN/rest.log" bus
bus_rc=0
listen 4 "$IN/silent.log" bus > "$RESULTS_DIR/silent_bus.txt" 2>&1 || bus_rc=$?
check bus_check_fails_on_a_silent_board test "$bus_rc" = 1
check bus_check_names_the_silent_board grep -q "    2     3        0.0           0.0     0  FAIL: absent" "$RESULTS_DIR/silent_bus.txt"

for s in taps jig sweep; do
  check "candump_records_the_${s}_session" record "$IN/$s.log" "$RESULTS_DIR/$s.candump"
done
check map_writes_its_dropin "${C[@]}" map --input "$RESULTS_DIR/taps.candump" --expect "$ORDER" -o "$ETC/whiskerd.d/10-map.yaml"
# The interactive map on the live bus: the operator's Enter after each whisker comes through a fifo,
# all of them once the taps have been played; it must find the wiring map found in the recording.
map_live() {
  local fifo=/tmp/map_enter
  rm -f "$fifo" && mkfifo "$fifo"
  "${C[@]}" map -i vcan0 --expect "$ORDER" -o "$RESULTS_DIR/map_live.yaml" < "$fifo" \
    > "$RESULTS_DIR/map_live.out" 2> "$RESULTS_DIR/map_live.err" &
  local pid=$!
  exec 3> "$fifo"
  wait_for "$RESULTS_DIR/map_live.err" "listening on vcan0" || echo "the tool did not start"
  wait_for "$RESULTS_DIR/map_live.out" "Hands off" || echo "no prompt"
  sleep 2.5
  canplayer -I "$IN/taps.log" vcan0=can0
  sleep 0.5
  local i
  for i in $(echo "$ORDER" | tr ',' ' '); do echo >&3; sleep 0.2; done
  exec 3>&-
  local rc=0
  wait $pid || rc=$?
  cat "$RESULTS_DIR/map_live.out" "$RESULTS_DIR/map_live.err"
  [ $rc = 0 ] || { echo "map exited $rc"; return 1; }
  grep -q "  moved: channel" "$RESULTS_DIR/map_live.out" || { echo "no push shown after an Enter"; return 1; }
  # (no /dev/fd in the guest: no process substitution)
  grep -o 'index: [0-9]*, channel: [0-9]*' "$RESULTS_DIR/map_live.yaml" > /tmp/map_live.channels
  grep -o 'index: [0-9]*, channel: [0-9]*' "$ETC/whiskerd.d/10-map.yaml" > /tmp/map_log.channels
  test -s /tmp/map_live.channels && diff /tmp/map_live.channels /tmp/map_log.channels
}
check map_live_interactive_finds_the_same_wiring map_live
# rest after map: the offsets go to the whiskers the map wired.
check rest_live_writes_its_dropin listen 5 "$IN/rest.log" rest -o "$ETC/whiskerd.d/20-rest.yaml"
check gain_writes_its_dropin "${C[@]}" gain --input "$RESULTS_DIR/jig.candump" --expect "$ORDER" --deflection 0.5 -o "$ETC/whiskerd.d/30-gain.yaml"
check theta_from_a_recorded_sweep "${C[@]}" theta --input "$RESULTS_DIR/sweep.candump" -o "$RESULTS_DIR/theta_recorded.yaml"
# theta on the live bus: whiskerd's control loop sweeps the closed-loop boards (board_sim_vm, the same
# true robot), first with board 0 reporting a fault after 5 s (refused), then whole.
sweep() {
  local fault=$1 seconds=$2 out=$3
  "$BOARDS" --interface vcan0 --truth-seed 5 --seconds $((seconds + 12)) ${fault:+--fault-at $fault} \
    > "$RESULTS_DIR/boards_$seconds.log" 2>&1 &
  local boards=$!
  local rc=0
  "${C[@]}" theta -i vcan0 --no-gpio --sweep-seconds "$seconds" -o "$out" > "$RESULTS_DIR/theta_$seconds.out" \
    2> "$RESULTS_DIR/theta_$seconds.err" || rc=$?
  kill $boards 2> /dev/null
  wait $boards
  cat "$RESULTS_DIR/theta_$seconds.err" "$RESULTS_DIR/boards_$seconds.log"
  return $rc
}
fault_rc=0
sweep 5 12 "$RESULTS_DIR/theta_fault.yaml" > "$RESULTS_DIR/sweep_fault.txt" 2>&1 || fault_rc=$?
check theta_live_refuses_a_sweep_interrupted_by_a_fault test "$fault_rc" = 1
check theta_live_names_the_fault grep -q "sweep interrupted by a fault: board 0" "$RESULTS_DIR/sweep_fault.txt"
check theta_live_writes_nothing_then test ! -e "$RESULTS_DIR/theta_fault.yaml"
check theta_live_sweeps_through_whiskerds_control_loop sweep "" 30 "$ETC/whiskerd.d/40-theta.yaml"
ls -l "$ETC/whiskerd.d"

"$CHECK" --truth "$IN/truth.yaml" --config "$ETC/whiskerd.yaml" --whiskers "$ORDER" \
  --results "$RESULTS_FILE" > "$RESULTS_DIR/check.log" 2>&1
exited_ok calibrate_vm_check_exits_0 $?
cat "$RESULTS_DIR/check.log"
exit 0
