#!/bin/bash
# VM scenario: camerad's MJPEG path against a kernel device. v4l2loopback (built for the guest kernel
# on the host, fixture vm.v4l2loopback_module) is fed known JPEG frames by mjpeg_loopback_writer;
# camerad negotiates MJPG on it and publishes CAMERA; mjpeg_vm_check decodes every published frame
# with slamd's decoder and compares it with the pattern written for its number. Meanwhile the writer
# damages frames (cut short, garbage after a valid header), goes silent and comes back, and last the
# device is removed and created again; each shows in camerad's DRIVER_STATUS.
#   scenario_camerad_mjpeg.sh RESULTS_DIR MODULE_DIR CAMERAD WRITER CHECK DRIVER_STATUS_PROBE
set -u
RESULTS_DIR=$1
MODULE=$2/v4l2loopback.ko
CAMERAD=$3
WRITER=$4
CHECK=$5
PROBE=$6
source "$(dirname "$0")/lib.sh"
# A command written to a writer that has gone must fail that write, not kill the scenario.
trap '' PIPE

setup_lcm_loopback
# One loopback device, /dev/video10, announcing capture and output at once (exclusive_caps=0), with
# 8 buffers (v4l2loopback's default is 2). camerad asks for the same 8 (buffers: 8 below): a reader
# asking for fewer makes v4l2loopback 0.12.7 shrink the ring under the running writer and remap its
# positions (vidioc_reqbufs), after which one position can name a buffer the writer fills next, and the
# reader got one frame twice (CI: "frame 7 after 7"). A UVC camera has no such remapping.
# Module autoloading would run the initramfs's modprobe: V4L2's core (videodev) is loaded explicitly.
load_loopback() {
  modprobe videodev && insmod "$MODULE" devices=1 video_nr=10 card_label=WhiskEye-MJPEG-loopback max_buffers=8
}
check v4l2loopback_loads load_loopback
check v4l2loopback_device_appears test -c /dev/video10
[ -c /dev/video10 ] || exit 0  # nothing below can run; the failures above say why

# The writer reads its commands from a FIFO the scenario holds open (fd 3) until it sends quit.
# start_writer LOG FIRST_NUMBER [WRITER_ARGS...]: the writer's pid in $writer.
start_writer() {
  rm -f /tmp/writer.cmd
  mkfifo /tmp/writer.cmd
  "$WRITER" --device /dev/video10 --fps 10 --first-number "$2" "${@:3}" < /tmp/writer.cmd > "$1" 2>&1 &
  writer=$!
  exec 3> /tmp/writer.cmd
}
say() { echo "$1" >&3 || echo "the writer is gone: '$1' not sent"; }
# camerad joins a writer that has gone round the ring and paused. v4l2loopback 0.12.7 re-initialises
# every buffer when a reader asks for buffers (VIDIOC_REQBUFS: sequence 0, bytesused the format's
# sizeimage), so camerad's first DQBUF hands it frame 11 followed by the rest of the longer frame 3
# that buffer held before: damaged bytes under a number that is not the frame's. camerad must give it
# back as a buffer from before its session, neither a frame nor damage. Paused, no write can refill
# the buffer first: without the pause it depends on when camerad opens (a busy host: late).
start_writer "$RESULTS_DIR/writer.log" 0 --pause-after 12
check writer_sets_mjpeg_on_the_device wait_for "$RESULTS_DIR/writer.log" "writing 640x480 MJPG" 30
check writer_pauses_after_going_round_the_ring wait_for "$RESULTS_DIR/writer.log" "paused after 12 frames" 30

cat > /tmp/camerad_mjpeg.yaml <<'YAML'
camera: {match_card: WhiskEye-MJPEG, width: 640, height: 480, fps: 10, formats: [MJPG], buffers: 8,
         frame_timeout_s: 4.0, reopen_initial_s: 0.2, reopen_max_s: 1.0}
YAML
log=$RESULTS_DIR/camerad.log
"$CAMERAD" -c /tmp/camerad_mjpeg.yaml > "$log" 2>&1 &
cam_pid=$!
"$CHECK" --results "$RESULTS_DIR/results.txt" > "$RESULTS_DIR/check.log" 2>&1 &
check_pid=$!
check camerad_negotiates_640x480_mjpg_on_the_loopback_device \
  wait_for "$log" "streaming /dev/video10 640x480 MJPG at 10 fps, 8 buffers" 60
check camerad_skips_the_buffer_v4l2loopback_reinitialised_before_its_stream \
  wait_for "$log" "skipping a buffer from before the stream started" 3
say resume

probe() { "$PROBE" --driver camerad --seconds "${2:-2}" "${@:3}" > "/tmp/status_$1.txt"; cp "/tmp/status_$1.txt" "$RESULTS_DIR/status_$1.txt"; }
counter() { probe_value "/tmp/status_$1.txt" "$2"; }
has() { probe_has "/tmp/status_$1.txt" "$2"; }  # has PROBE 'name=regex'
# Frames camerad skipped as damaged, less those it found overwritten while it read them:
# v4l2loopback 0.12.7 writes its 8-buffer ring round whether or not a reader still holds a buffer,
# so a frame camerad reads more than ~0.6 s after it was written (a TCG guest on a busy host) is
# torn, and counted in corrupt_frames and overwritten_frames. What is left is what the writer damaged.
damaged() { echo $(( $(counter "$1" corrupt_frames) - $(counter "$1" overwritten_frames) )); }
# grew PROBE_BEFORE PROBE_AFTER N: the frames damaged by the writer went up by exactly N between the
# two probes.
grew() {
  local before after
  before=$(damaged "$1") after=$(damaged "$2")
  [ $((after - before)) -eq "$3" ] && return 0
  echo "damaged frames (corrupt_frames - overwritten_frames) went from $before to $after, expected +$3" \
       "(overwritten_frames $(counter "$2" overwritten_frames))"
  return 1
}

sleep 3
probe streaming
clean_stream() {
  has streaming 'state=1' && has streaming 'frames=([1-9][0-9]+)' && [ "$(damaged streaming)" = 0 ] ||
    { echo "damaged frames: $(damaged streaming) (corrupt_frames $(counter streaming corrupt_frames)," \
           "overwritten_frames $(counter streaming overwritten_frames))"; return 1; }
}
check camerad_is_ok_and_counts_no_damaged_frame_in_a_clean_stream clean_stream

# Three frames cut short (their first half: no end-of-image marker), then three whose data after a
# valid header is garbage: each skipped and counted, logged once per kind, the stream going on.
say "cut 3"
sleep 2
probe cut
check camerad_counts_each_frame_cut_short grew streaming cut 3
check camerad_logs_a_frame_cut_short grep -q "skipping a frame cut short (no JPEG end-of-image marker)" "$log"
say "garbage 3"
sleep 2
probe garbage
check camerad_counts_each_frame_with_garbage_after_its_header grew cut garbage 3
check camerad_logs_a_frame_with_garbage grep -q "skipping a frame with damaged JPEG data after its header" "$log"
check camerad_stays_ok_through_damaged_frames has garbage 'state=1'

# The camera goes silent (the device stays open): DEGRADED, "no frame", then OK when frames return.
say pause
sleep 1.5
probe silent 4 --until-state 2 --until-message "no frame"  # whenever a status falls in it
silent() { has silent 'state=2' && has silent 'message=.*no frame.*'; }
check camerad_is_degraded_while_the_camera_is_silent silent
say resume
sleep 3
probe resumed
check camerad_is_ok_again_when_the_camera_resumes has resumed 'state=1'
resumed_frames() {
  [ "$(counter resumed frames)" -gt "$(counter silent frames)" ] ||
    { echo "frames $(counter silent frames) while silent, $(counter resumed frames) after"; return 1; }
}
check camerad_publishes_again_after_the_silence resumed_frames

# The device removed and created again. v4l2loopback 0.12.7 cannot remove a device while it is open
# (an open file pins the module; there is no remove ioctl before 0.13), so the camera stops first:
# the writer exits, camerad closes the silent device after frame_timeout_s and retries it, and the
# module is unloaded between two of its tries.
say quit
exec 3>&-
wait $writer
cat "$RESULTS_DIR/writer.log"
unload_loopback() {
  for _ in $(seq 60); do rmmod v4l2loopback 2>/dev/null && return 0; sleep 0.2; done
  rmmod v4l2loopback
}
check v4l2loopback_unloads_once_camerad_lets_go unload_loopback
check camerad_closes_the_silent_device wait_for "$log" "/dev/video10: no frames; closing and reopening" 10
check camerad_says_the_camera_is_gone \
  wait_for "$log" "no V4L2 capture device whose card or driver contains 'WhiskEye-MJPEG'" 10
probe gone 2
check camerad_is_degraded_without_a_camera has gone 'state=2'
check v4l2loopback_loads_again load_loopback
start_writer "$RESULTS_DIR/writer2.log" 10000
# Two "streaming" lines: the first session and the one after the device came back (up to 20 s).
streams_again() {
  for _ in $(seq 100); do
    [ "$(grep -c 'streaming /dev/video10 640x480 MJPG' "$log")" -ge 2 ] && return 0
    sleep 0.2
  done
  echo "$(grep -c 'streaming /dev/video10 640x480 MJPG' "$log") streaming line(s) in camerad's log after 20 s"
  return 1
}
check camerad_reopens_the_recreated_device streams_again
sleep 3
probe back
check camerad_is_ok_on_the_recreated_device has back 'state=1'
check camerad_status_counts_the_loss_and_the_reopen \
  bash -c "[ $(counter back device_lost) -ge 1 ] && [ $(counter back reopens) -ge 1 ] && [ $(counter back open_failures) -ge 1 ]"
# Across the writer's stop, the removal and the re-creation the writer damaged nothing. camerad
# reopens the new device while the new writer streams, so its first buffer is again one
# v4l2loopback re-initialised (above), whose bytes may read as damaged: skipped, not counted.
check camerad_counts_no_damaged_frame_across_the_writers_stop_and_the_new_device grew garbage back 0

kill -TERM $check_pid
check_rc=0
wait $check_pid || check_rc=$?
cat "$RESULTS_DIR/check.log"
exited_ok mjpeg_vm_check_exits_0 "$check_rc"
say quit
exec 3>&-
wait $writer
kill -TERM $cam_pid
wait $cam_pid
check camerad_exits_cleanly_on_sigterm test $? = 0
exit 0
