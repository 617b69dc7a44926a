#!/bin/bash
# VM scenario: whiskerd's motor lines (libgpiod) against a real gpiochip, the kernel's gpio-mockup
# driver built by build_guest_module.sh on the host (a ctest fixture) and loaded here with three named
# lines (enable, fault, e-stop): first the lines alone (gpio_vm_check), then whiskerd using them, idle
# and then driving its motors while vita-sim's candump log (fixture vm.sim_replay_inputs) streams.
#   scenario_gpio.sh RESULTS_DIR CHECK MODULE_DIR WHISKERD WHISKERD_CONFIG SIM_REPLAY_INPUTS
set -u
RESULTS_DIR=$1
CHECK=$2
MODULE=$3/gpio-mockup.ko
WHISKERD=$4
BASE_CONFIG=$5
IN=$6
source "$(dirname "$0")/lib.sh"

mountpoint -q /sys/kernel/debug || mount -t debugfs none /sys/kernel/debug
check gpio_mockup_module_loads insmod "$MODULE" gpio_mockup_ranges=-1,3 gpio_mockup_named_lines=1
chip=$(ls -d /sys/kernel/debug/gpio-mockup/gpiochip* 2>/dev/null | head -1)
check gpio_mockup_chip_appears test -n "$chip"
gpioinfo 2>/dev/null | grep -A3 gpio-mockup || true
check_rc=0
"$CHECK" --chip-debugfs "$chip" --results "$RESULTS_DIR/results.txt" || check_rc=$?
exited_ok gpio_vm_check_exits_0 "$check_rc"

# whiskerd on vcan0 (no boards: the motors stay off) with its lines on the mockup.
setup_lcm_loopback
setup_vcan vcan0
config=/tmp/whiskerd_gpio.yaml
write_gpio_config "$BASE_CONFIG" "$config"
sed 's/fault_line: gpio-mockup-A-1/fault_line: WHISKER_MOTOR_FAULT/' "$config" > /tmp/whiskerd_missing.yaml
echo 1 > "$chip/1"  # fault and e-stop idle (active low)
echo 1 > "$chip/2"

"$WHISKERD" -c /tmp/whiskerd_missing.yaml > "$RESULTS_DIR/whiskerd_missing.log" 2>&1
code=$?
cat "$RESULTS_DIR/whiskerd_missing.log"
check whiskerd_without_its_fault_line_exits_1_naming_it \
  sh -c "test $code = 1 && grep -q WHISKER_MOTOR_FAULT '$RESULTS_DIR/whiskerd_missing.log'"

log=$RESULTS_DIR/whiskerd.log
"$WHISKERD" -c "$config" > "$log" 2>&1 &
wd=$!
check whiskerd_opens_the_mockup_lines wait_for "$log" "gpiod lines enable=gpio-mockup-A-0 fault=gpio-mockup-A-1"
check whiskerd_keeps_the_motors_off_without_boards test "$(cat "$chip/0")" = 0
sleep 1
echo 0 > "$chip/1"  # a fault pulse shorter than a control period
echo 1 > "$chip/1"
check whiskerd_latches_a_fault_pulse_on_the_real_line wait_for "$log" "motor fault / emergency stop: motors disabled"
kill -TERM $wd
wait $wd
code=$?
cat "$log"
check whiskerd_stops_cleanly test $code = 0

# With every board streaming (the simulated boards replayed by canplayer) whiskerd powers the motors:
# the enable line goes high; a fault pulse drops it at once and it stays low (latched) while the
# boards go on streaming.
# poll_enable VALUE: up to 10 s for the enable line to read VALUE.
poll_enable() {
  for _ in $(seq 500); do [ "$(cat "$chip/0")" = "$1" ] && return 0; sleep 0.02; done
  echo "the enable line reads $(cat "$chip/0") after 10 s, expected $1"
  return 1
}
# start_streaming LOG: whiskerd (pid in $wd, output in LOG) with the simulated boards replayed to
# it (canplayer's pid in $player).
start_streaming() {
  log=$1
  "$WHISKERD" -c "$config" > "$log" 2>&1 &
  wd=$!
  wait_for "$log" "gpiod lines enable=" || echo "whiskerd did not start"
  canplayer -I "$IN/sim_fd.candump" vcan0=can0 &
  player=$!
}
start_streaming "$RESULTS_DIR/whiskerd_streaming.log"
check enable_goes_high_once_every_board_streams poll_enable 1
echo 0 > "$chip/1"
echo 1 > "$chip/1"
check a_fault_pulse_drops_the_enable_line poll_enable 0
check whiskerd_reports_the_fault wait_for "$log" "motor fault / emergency stop: motors disabled"
wait $player
check the_fault_stays_latched_to_the_end_of_the_stream test "$(cat "$chip/0")" = 0
stop_daemon $wd whiskerd
check whiskerd_exits_on_sigterm_with_the_fault_latched test $stopped_rc != 124
cat "$log"

# SIGTERM while the motors are powered: whiskerd retracts, then drops the enable line before it exits.
# The line's value after the exit proves nothing (gpio-mockup sets a released line to its pull), so
# the kernel's gpio_value trace event records what whiskerd itself wrote to the line, in order.
tracing=/sys/kernel/tracing
mountpoint -q "$tracing" || mount -t tracefs nodev "$tracing"
check gpio_trace_events_available test -w "$tracing/events/gpio/gpio_value/enable"
enable_gpio=$(sed -n "s/^$(basename "$chip"): GPIOs \([0-9]*\)-.*/\1/p" /sys/kernel/debug/gpio)
check enable_line_number_known test -n "$enable_gpio"
echo > "$tracing/trace"
echo 1 > "$tracing/events/gpio/gpio_value/enable"
start_streaming "$RESULTS_DIR/whiskerd_sigterm.log"
check enable_goes_high_again_with_the_boards_streaming poll_enable 1
stop_daemon $wd whiskerd
code=$stopped_rc
echo 0 > "$tracing/events/gpio/gpio_value/enable"
grep -E "gpio_value: $enable_gpio set [01]" "$tracing/trace" > "$RESULTS_DIR/enable_trace.txt"
tail -3 "$RESULTS_DIR/enable_trace.txt"
check whiskerd_stops_cleanly_while_powered test $code = 0
check whiskerd_drove_the_enable_line_high grep -q "set 1$" "$RESULTS_DIR/enable_trace.txt"
check whiskerd_itself_drove_the_enable_line_low_last \
  sh -c "tail -1 '$RESULTS_DIR/enable_trace.txt' | grep -q 'set 0$'"
check whiskerd_retracted_then_stopped \
  sh -c "grep -A1 'running -> retracting (stopping: retracting)' '$log' | grep -q 'retracting -> stopped'"
kill $player 2>/dev/null
wait $player 2>/dev/null
cat "$log"
exit 0
