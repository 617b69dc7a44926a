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

# Faults injected through vivid's own controls into a running camerad (640x480 YUYV at 5 fps): each
# shows in DRIVER_STATUS, and camerad streams on or recovers by itself.
printf 'camera: {match_card: vivid}\n' > /tmp/faults.yaml
"$CAMERAD" -c /tmp/faults.yaml > "$RESULTS_DIR/camerad_faults.log" 2>&1 &
faults_pid=$!
wait_for "$RESULTS_DIR/camerad_faults.log" streaming 60 || true
probe() { "$PROBE" --driver camerad --seconds "${2:-3}" "${@:3}" > "/tmp/faults_$1.txt"; cp "/tmp/faults_$1.txt" "$RESULTS_DIR/status_$1.txt"; }
counter() { probe_value "/tmp/faults_$1.txt" "$2"; }
has() { probe_has "/tmp/faults_$1.txt" "$2"; }  # has PROBE 'name=regex'
ctl() { v4l2-ctl -d /dev/video0 -c "$1"; }
probe streaming
check camerad_is_ok_while_frames_arrive has streaming 'state=1'
# One buffer flagged V4L2_BUF_FLAG_ERROR, one VIDIOC_QBUF that fails: skipped and counted; the
# buffer whose QBUF failed is given back at the next call, so the stream goes on at full rate.
ctl inject_v4l2_buf_flag_error=1
sleep 1
ctl inject_vidioc_qbuf_error=1
sleep 2
probe injected
check camerad_counts_a_buffer_the_driver_flagged_as_damaged has injected 'corrupt_frames=[1-9][0-9]*'
check camerad_counts_a_failed_requeue has injected 'requeue_failures=[1-9][0-9]*'
sleep 2
probe after_requeue
streams_on() {
  [ $(( $(counter after_requeue frames) - $(counter injected frames) )) -ge 5 ] ||
    { echo "frames $(counter injected frames) then $(counter after_requeue frames), expected 5 more"; return 1; }
  has after_requeue 'state=1'
}
check camerad_streams_on_after_a_failed_requeue streams_on
# Half the buffers dropped by the driver: the sequence numbers say how many.
ctl percentage_of_dropped_buffers=50
sleep 3
probe dropping
check camerad_counts_frames_the_driver_dropped has dropping 'sequence_gaps=[1-9][0-9]*'
# All of them: still open, but DEGRADED, saying no frame arrives (then reopened after frame_timeout).
ctl percentage_of_dropped_buffers=100
sleep 1
probe silent 4 --until-state 2 --until-message "no frame"  # whenever a status falls in it
degraded() { has silent 'state=2' && has silent 'message=.*no frame.*'; }
check camerad_is_degraded_while_open_but_silent degraded
ctl percentage_of_dropped_buffers=0
sleep 4
probe back
check camerad_is_ok_again_when_frames_return has back 'state=1'
# A fatal streaming error (vb2_queue_error: DQBUF fails with EIO): closed, reopened, streaming again.
ctl inject_fatal_streaming_error=1
wait_for "$RESULTS_DIR/camerad_faults.log" "closing and reopening" 20 || true
sleep 4
probe after_fatal
reopened() {
  [ "$(counter back device_lost)" -lt "$(counter after_fatal device_lost)" ] ||
    { echo "device_lost $(counter back device_lost) then $(counter after_fatal device_lost), expected more"; return 1; }
  has after_fatal 'state=1'
}
check camerad_reopens_after_a_fatal_streaming_error reopened
kill -TERM $faults_pid
wait $faults_pid
check camerad_survives_the_injected_faults test $? = 0

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
