#!/bin/bash
# VM scenario: vita-sim's candump log replayed by can-utils' canplayer into vcan0 (interface mapping
# vcan0=can0) in front of the real whiskerd; whiskerd's WHISKER_SAMPLE must be the simulated samples
# (vita-sim's LCM log of the same run) within one count. CAN FD at 500 Hz, then classic CAN at 100 Hz.
# whiskerd's motor commands are ignored: this is an open-loop replay. The logs and configs come from
# the host (sim_replay_inputs.sh, a ctest fixture) in INPUTS.
#   scenario_sim_replay.sh RESULTS_DIR WHISKERD CHECK INPUTS
set -u
RESULTS_DIR=$1
WHISKERD=$2
CHECK=$3
IN=$4
source "$(dirname "$0")/lib.sh"

setup_lcm_loopback
setup_vcan vcan0

# run_mode MODE PREFIX
run_mode() {
  local mode=$1 prefix=$2 config=$IN/whiskerd_$1.yaml
  head -n 3 "$IN/sim_$mode.candump"
  "$CHECK" --sim-log "$IN/sim.lcmlog" --control-log "$IN/control.lcmlog" --config "$config" \
    --results "$RESULTS_DIR/results.txt" --prefix "$prefix" > "$RESULTS_DIR/check_$mode.log" 2>&1 &
  local check_pid=$!
  "$WHISKERD" -c "$config" --no-gpio > "$RESULTS_DIR/whiskerd_$mode.log" 2>&1 &
  local wd_pid=$!
  # Replay once the checker listens and whiskerd has opened the bus.
  wait_for "$RESULTS_DIR/check_$mode.log" "^listening on" || echo "the checker did not start"
  wait_for "$RESULTS_DIR/whiskerd_$mode.log" "^whiskerd: vcan0 (" || echo "whiskerd did not start"
  sleep 0.3
  check "${prefix}canplayer_replays_the_candump_with_interface_mapping" \
    canplayer -I "$IN/sim_$mode.candump" vcan0=can0
  local check_rc=0
  wait $check_pid || check_rc=$?
  cat "$RESULTS_DIR/check_$mode.log"
  exited_ok "${prefix}sim_replay_check_exits_0" "$check_rc"
  kill -TERM $wd_pid
  wait $wd_pid
  check "${prefix}whiskerd_exits_cleanly_after_the_replay" test $? = 0
}

start=$SECONDS
for f in sim.lcmlog control.lcmlog sim_fd.candump sim_classic.candump; do
  check "input_${f//./_}_present" test -s "$IN/$f"
done
run_mode fd ""
echo "CAN FD replay: $((SECONDS - start)) s"
ip -s link show vcan0
start=$SECONDS
run_mode classic classic_
echo "classic replay: $((SECONDS - start)) s"
exit 0
