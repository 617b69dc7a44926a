#!/bin/bash
# Diagnostic, not a ctest test (issue 52, item 17: whiskerd once did not exit after its last line in
# about 35 vm.gpio runs): vm.gpio's last phase N times in one guest, so that one boot gives N chances
# of the hang instead of one. whiskerd starts on the gpio-mockup lines with the boards streaming (the
# gpio_value trace event on, as in vm.gpio; a fault pulse every third time), is SIGTERMed while
# powered, and runs under strace (close, ioctl, write, exit_group, each timed): per stop, the time
# from its last line to its exit and the longest call after that line (the trace kept when it is over
# 0.1 s); one still running 20 s after SIGTERM gets each thread's state, wait channel, system call,
# kernel stack and gdb backtrace printed, then is killed. From the build tree:
#   tests/vm/run-vm WORK tests/vm/stress_gpio_stops.sh 900 build/tests/vm/gpio_mockup_module \
#     build/bin/whiskerd tests/vm/whiskerd_vm.yaml build/tests/vm/sim_replay_inputs 300
# (absolute paths; the fixtures vm.gpio_mockup_module and vm.sim_replay_inputs made first).
set -u
RESULTS_DIR=$1
MODULE=$2/gpio-mockup.ko
WHISKERD=$3
BASE_CONFIG=$4
IN=$5
N=${6:-40}
source "$(dirname "$0")/lib.sh"
mountpoint -q /sys/kernel/debug || mount -t debugfs none /sys/kernel/debug
check gpio_mockup_module_loads insmod "$MODULE" gpio_mockup_ranges=-1,3 gpio_mockup_named_lines=1
chip=$(ls -d /sys/kernel/debug/gpio-mockup/gpiochip* 2>/dev/null | head -1)
setup_lcm_loopback
setup_vcan vcan0
config=/tmp/whiskerd_gpio.yaml
write_gpio_config "$BASE_CONFIG" "$config"
echo 1 > "$chip/1"
echo 1 > "$chip/2"
poll_enable() {
  for _ in $(seq 500); do [ "$(cat "$chip/0")" = "$1" ] && return 0; sleep 0.02; done
  return 1
}
tracing=/sys/kernel/tracing
mountpoint -q "$tracing" || mount -t tracefs nodev "$tracing"
echo 1 > "$tracing/events/gpio/gpio_value/enable"
hung=0
for k in $(seq "$N"); do
  log=$RESULTS_DIR/w.log
  strace -f -tt -T -e trace=close,ioctl,exit_group,write -o /tmp/st.txt "$WHISKERD" -c "$config" > "$log" 2>&1 &
  spid=$!
  wd=""
  for _ in $(seq 400); do wd=$(pgrep -P "$spid" -x whiskerd); [ -n "$wd" ] && break; sleep 0.05; done
  [ -n "$wd" ] || { echo "iteration $k: whiskerd did not start under strace"; kill "$spid"; wait "$spid"; continue; }
  wait_for "$log" "gpiod lines enable=" >/dev/null || echo "iteration $k: whiskerd did not start"
  canplayer -I "$IN/sim_fd.candump" vcan0=can0 &
  player=$!
  poll_enable 1 || echo "iteration $k: enable not high"
  sleep 0.$((RANDOM % 10))
  if [ $((k % 3)) = 0 ]; then echo 0 > "$chip/1"; echo 1 > "$chip/1"; sleep 0.2; fi
  t0=$(date +%s.%N)
  kill -TERM "$wd"
  for _ in $(seq 2000); do running "$wd" || break; sleep 0.01; done
  t1=$(date +%s.%N)
  if running "$wd"; then
    hung=$((hung + 1))
    echo "iteration $k: whiskerd (pid $wd) still running 20 s after SIGTERM"
    tail -3 "$log"
    for t in /proc/"$wd"/task/*; do
      echo "  thread $(basename "$t") $(cat "$t/comm") state $(awk '{print $3}' "$t/stat") wchan $(cat "$t/wchan") syscall $(cat "$t/syscall")"
      sed 's/^/    /' "$t/stack" 2>/dev/null
    done
    ls -l /proc/"$wd"/fd
    timeout 60 gdb -p "$wd" -batch -ex "thread apply all bt" 2>&1 | tail -60
    kill -KILL "$wd"
    cp "$log" "$RESULTS_DIR/hung-$k.log"
  fi
  wait "$spid" 2>/dev/null
  rc=$?
  post=$(awk '/stopped, motors/{on=1; split($2,a,":"); t0=a[1]*3600+a[2]*60+a[3]} on{split($2,b,":"); t=b[1]*3600+b[2]*60+b[3]; if ($0 ~ /exited with|exit_group/) last=t; d=$NF; gsub(/[<>]/,"",d); if (d+0>m) {m=d+0; w=$0}} END{printf "%.3f s from the last line to the exit; longest call after it %.3f s: %s", last-t0, m, w}' /tmp/st.txt)
  echo "iteration $k: $post"
  case "$post" in [1-9]*|0.[1-9]*) cp /tmp/st.txt "$RESULTS_DIR/strace-$k.txt" ;; esac
  kill "$player" 2>/dev/null
  wait "$player" 2>/dev/null
  echo "iteration $k: rc $rc, exited $(echo "$t1 - $t0" | bc) s after SIGTERM"
  echo > "$tracing/trace"
done
check no_hang test "$hung" = 0
exit 0
