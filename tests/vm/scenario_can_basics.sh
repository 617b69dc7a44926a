#!/bin/bash
# VM scenario: the kernel's vcan + can-raw work with FD frames (proves the harness and the bus).
set -u
RESULTS_DIR=$1
source "$(dirname "$0")/lib.sh"

check vcan_fd_link_up setup_vcan vcan0
check vcan_mtu_is_fd bash -c 'ip link show vcan0 | grep -q "mtu 72"'

timeout 10 candump -L -n 2 vcan0 > /tmp/dump.txt &
dump_pid=$!
sleep 0.3
cansend vcan0 123#DEADBEEF
cansend vcan0 '18F##1'"$(printf '%02X' $(seq 0 47) | tr -d ' ')"
wait $dump_pid
cp /tmp/dump.txt "$RESULTS_DIR/candump.txt"
check classic_frame_round_trip grep -q 'vcan0 123#DEADBEEF' /tmp/dump.txt
# The flags nibble after ## depends on the can-utils version (BRS, plus FDF in newer ones).
check fd_frame_round_trip grep -Eq 'vcan0 18F##[0-9A-F]000102.*2E2F$' /tmp/dump.txt
