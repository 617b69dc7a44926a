#!/bin/bash
# VM scenario: the kernel's vcan + can-raw work with FD frames (proves the harness and the bus).
set -u
RESULTS_DIR=$1
source "$(dirname "$0")/lib.sh"

check vcan_fd_link_up setup_vcan vcan0
check vcan_mtu_is_fd bash -c 'ip link show vcan0 | grep -q "mtu 72"'

# One listener per frame; the frames are re-sent until both listeners have one, since a listener
# started in the background on an emulated CPU may take a while to bind.
timeout 20 candump -L -n 1 vcan0,123:7FF > /tmp/classic.txt &
classic_pid=$!
timeout 20 candump -L -n 1 vcan0,18F:7FF > /tmp/fd.txt &
fd_pid=$!
fd_data=$(printf '%02X' $(seq 0 47) | tr -d ' ')
for i in $(seq 1 100); do
  cansend vcan0 123#DEADBEEF
  cansend vcan0 "18F##1$fd_data"
  kill -0 $classic_pid 2>/dev/null || kill -0 $fd_pid 2>/dev/null || break
  sleep 0.2
done
wait $classic_pid $fd_pid
cat /tmp/classic.txt /tmp/fd.txt > "$RESULTS_DIR/candump.txt"
check classic_frame_round_trip grep -q 'vcan0 123#DEADBEEF$' /tmp/classic.txt
# The flags nibble after ## depends on the can-utils version (BRS, plus FDF in newer ones).
check fd_frame_round_trip grep -Eq 'vcan0 18F##[0-9A-F]000102.*2E2F$' /tmp/fd.txt
