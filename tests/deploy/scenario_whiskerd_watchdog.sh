#!/bin/bash
# VM scenario: whiskerd on vcan0 (no boards attached; the control loop runs regardless) under the
# notify/watchdog check: READY=1, WATCHDOG=1 from the control loop's progress, none once the control
# loop is stalled by the test-only fault injection, clean exit on SIGINT.
#   scenario_whiskerd_watchdog.sh RESULTS_DIR WHISKERD WATCHDOG_VM_CHECK
set -u
RESULTS_DIR=$1
WHISKERD=$2
CHECK=$3
source "$(dirname "$0")/../vm/lib.sh"

setup_lcm_loopback
setup_vcan vcan0

# TCG emulation is slow: a 1 s watchdog (keep-alives every 0.5 s) and more time before the stall.
check whiskerd_sends_ready_and_watchdog_from_its_control_loop_and_stops_when_it_stalls \
  bash -c "'$CHECK' --watchdog-usec 1000000 --stall-after 8 --window 3 -- '$WHISKERD' -i vcan0 --no-gpio \
           > '$RESULTS_DIR/whiskerd_watchdog.log' 2>&1; rc=\$?; head -n 3 '$RESULTS_DIR/whiskerd_watchdog.log'; exit \$rc"
cat "$RESULTS_DIR/whiskerd_watchdog.log"
exit 0
