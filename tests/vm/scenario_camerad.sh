#!/bin/bash
# VM scenario: camerad captures from vivid (a virtual V4L2 camera in the guest kernel); mid-stream the
# device is unbound and the driver unloaded and reloaded; camerad must recover on its own.
#   scenario_camerad.sh RESULTS_DIR CAMERAD CAMERA_VM_CHECK CONFIG DRIVER_STATUS_PROBE
set -u
RESULTS_DIR=$1
CAMERAD=$2
CHECK=$3
CONFIG=$4
PROBE=$5
source "$(dirname "$0")/lib.sh"

setup_lcm_loopback
# One vivid instance with only a video capture node (input 0: a webcam with 640x480 at 5 fps).
load_vivid() { modprobe vivid n_devs=1 node_types=0x1; }
check vivid_loads load_vivid
check vivid_offers_640x480_yuyv bash -c "v4l2-ctl -d /dev/video0 --list-formats-ext | grep -q YUYV"

# A mode vivid does not offer (no MJPEG, no 700x500): camerad takes the nearest and says so.
printf 'camera: {match_card: vivid, width: 700, height: 500, formats: [MJPG, YUYV]}\n' > /tmp/fallback.yaml
"$CAMERAD" -c /tmp/fallback.yaml > "$RESULTS_DIR/camerad_fallback.log" 2>&1 &
fb_pid=$!
wait_for "$RESULTS_DIR/camerad_fallback.log" streaming 60 || true
kill -TERM $fb_pid
wait $fb_pid
check camerad_logs_the_fallback_to_the_nearest_mode \
  grep -q "700x500 MJPG not supported, using the nearest mode [0-9]*x[0-9]* YUYV" "$RESULTS_DIR/camerad_fallback.log"
check camerad_streams_in_the_fallback_mode grep -q "streaming /dev/video[0-9]* [0-9]*x[0-9]* YUYV" "$RESULTS_DIR/camerad_fallback.log"

# Grey frames (8-bit mono cameras): captured and published, none refused as damaged.
printf 'camera: {match_card: vivid, formats: [GREY]}\n' > /tmp/grey.yaml
"$CAMERAD" -c /tmp/grey.yaml > "$RESULTS_DIR/camerad_grey.log" 2>&1 &
grey_pid=$!
wait_for "$RESULTS_DIR/camerad_grey.log" streaming 60 || true
"$PROBE" --driver camerad --seconds 4 > /tmp/grey_status.txt
cat /tmp/grey_status.txt
kill -TERM $grey_pid
wait $grey_pid
check camerad_streams_grey grep -q "streaming /dev/video[0-9]* 640x480 GREY" "$RESULTS_DIR/camerad_grey.log"
check camerad_publishes_grey_frames_none_damaged \
  bash -c "grep -Eq '^frames=([5-9]|[1-9][0-9]+)$' /tmp/grey_status.txt && grep -q '^corrupt_frames=0$' /tmp/grey_status.txt"

"$CAMERAD" -c "$CONFIG" > "$RESULTS_DIR/camerad.log" 2>&1 &
cam_pid=$!
"$CHECK" --seconds 60 --results "$RESULTS_DIR/results.txt" > "$RESULTS_DIR/check.log" 2>&1 &
check_pid=$!

# Let camerad stream for a couple of seconds first (startup on an emulated CPU is slow).
wait_for "$RESULTS_DIR/camerad.log" streaming 60 || true
sleep 3
# The device disappears under camerad (as an unplug would), then the driver is unloaded and
# reloaded. Unbinding first releases camerad's hold on the module so rmmod cannot fail "in use".
echo vivid.0 > /sys/bus/platform/drivers/vivid/unbind
sleep 1
unload_vivid() {
  for i in 1 2 3 4 5 6 7 8 9 10; do rmmod vivid 2>/dev/null && return 0; sleep 0.3; done
  rmmod vivid
}
check vivid_unloads_mid_stream unload_vivid
check vivid_reloads load_vivid

check_rc=0
wait $check_pid || check_rc=$?
cat "$RESULTS_DIR/check.log"
exited_ok camera_vm_check_exits_0 "$check_rc"
kill -TERM $cam_pid
wait $cam_pid
check camerad_exits_cleanly_on_sigterm test $? = 0
check camerad_logged_the_loss grep -q "reopening" "$RESULTS_DIR/camerad.log"
exit 0
