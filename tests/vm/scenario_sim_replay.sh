#!/bin/bash
# VM scenario: vita-sim's candump log replayed by can-utils' canplayer into vcan0 (interface mapping
# vcan0=can0) in front of the real whiskerd; whiskerd's WHISKER_SAMPLE must be the simulated samples
# (vita-sim's LCM log of the same run) within one count. CAN FD at 500 Hz, then classic CAN at 100 Hz.
# whiskerd's motor commands are ignored: this is an open-loop replay.
#   scenario_sim_replay.sh RESULTS_DIR WHISKERD VITA_SIM CHECK CONFIG SOURCE_DIR
set -u
RESULTS_DIR=$1
WHISKERD=$2
VITA_SIM=$3
CHECK=$4
CONFIG=$5
SRC=$6
source "$(dirname "$0")/lib.sh"

setup_lcm_loopback
setup_vcan vcan0

# The arena started where the robot passes box_north within 2 s: contacts and saturated deflections.
sed 's/start_angle_deg: .*/start_angle_deg: 84/' "$SRC/config/worlds/aliased_arena.yaml" > /tmp/contact_world.yaml

# wait_for FILE PATTERN: up to 30 s for a line (a TCG guest starts programs slowly).
wait_for() {
  for _ in $(seq 300); do grep -q "$2" "$1" 2>/dev/null && return 0; sleep 0.1; done
  return 1
}

# run_mode MODE CONFIG PREFIX
run_mode() {
  local mode=$1 config=$2 prefix=$3
  # 2 simulated seconds; the log names the head's bus can0, as a recording on the robot would. The
  # same run with another seed is the checker's negative control.
  local sim=("$VITA_SIM" --world /tmp/contact_world.yaml --robot "$SRC/config/robot.yaml" --duration 2 -q)
  if ! "${sim[@]}" --whiskerd-config "$config" --can-interface can0 --seed 11 \
      -o "/tmp/sim_$mode.lcmlog" --candump "/tmp/sim_$mode.candump" > "$RESULTS_DIR/vita_sim_$mode.log" 2>&1 ||
     ! "${sim[@]}" --seed 12 -o "/tmp/control_$mode.lcmlog" >> "$RESULTS_DIR/vita_sim_$mode.log" 2>&1; then
    fail "${prefix}vita_sim_writes_the_candump" "$(tail -n 2 "$RESULTS_DIR/vita_sim_$mode.log" | tr '\n' ' ')"
    return
  fi
  pass "${prefix}vita_sim_writes_the_candump"
  head -n 3 "/tmp/sim_$mode.candump"
  "$CHECK" --sim-log "/tmp/sim_$mode.lcmlog" --control-log "/tmp/control_$mode.lcmlog" --config "$config" \
    --results "$RESULTS_DIR/results.txt" --prefix "$prefix" > "$RESULTS_DIR/check_$mode.log" 2>&1 &
  local check_pid=$!
  "$WHISKERD" -c "$config" --no-gpio > "$RESULTS_DIR/whiskerd_$mode.log" 2>&1 &
  local wd_pid=$!
  # Replay once the checker listens and whiskerd has opened the bus.
  wait_for "$RESULTS_DIR/check_$mode.log" "^listening on" || echo "the checker did not start"
  wait_for "$RESULTS_DIR/whiskerd_$mode.log" "^whiskerd: vcan0 (" || echo "whiskerd did not start"
  sleep 0.3
  check "${prefix}canplayer_replays_the_candump_with_interface_mapping" \
    canplayer -I "/tmp/sim_$mode.candump" vcan0=can0
  wait $check_pid || echo "$mode checker reported failures"
  cat "$RESULTS_DIR/check_$mode.log"
  kill -TERM $wd_pid
  wait $wd_pid
  check "${prefix}whiskerd_exits_cleanly_after_the_replay" test $? = 0
}

run_mode fd "$CONFIG" ""
ip -s link show vcan0
sed 's/^can:$/can:\n  mode: classic/' "$CONFIG" > /tmp/whiskerd_classic.yaml
run_mode classic /tmp/whiskerd_classic.yaml classic_
exit 0
