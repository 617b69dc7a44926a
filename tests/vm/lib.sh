# Helpers for VM scenario scripts (sourced inside the guest; $1 of the scenario is the results dir).
RESULTS_DIR=${RESULTS_DIR:?}
RESULTS_FILE=$RESULTS_DIR/results.txt

pass() { echo "PASS $1" >> "$RESULTS_FILE"; echo "PASS $1"; }
fail() { echo "FAIL $1: $2" >> "$RESULTS_FILE"; echo "FAIL $1: $2"; }
# check NAME COMMAND...: one reported test per call. A failure says what was seen: the last lines the
# command printed (the scenarios' predicates print the value they saw when they fail), else the
# command as it ran, its arguments expanded (`test 1 = 0`: the value was 1), and for a grep of a
# file the file's last line.
check() {
  local name=$1; shift
  local out seen
  if out=$("$@" 2>&1); then pass "$name"; return; fi
  seen=$(echo "$out" | tail -n 3 | tr '\n' ' ')
  if [ -z "${seen// /}" ]; then
    seen="false: $*"
    if [ "$1" = grep ] && [ -f "${!#}" ]; then seen+="; last line of ${!#}: $(tail -n 1 "${!#}")"; fi
  fi
  fail "$name" "$seen"
}
# exited_ok NAME STATUS: one reported test that a checker program ran to its end. A checker writes its
# own PASS/FAIL lines as it goes or at its end; one that crashes or cannot start would otherwise
# leave only the scenario's checks behind, all passing.
exited_ok() {
  if [ "$2" = 0 ]; then pass "$1"; else fail "$1" "exit status $2 (its log is in the results folder)"; fi
}
# wait_for FILE PATTERN [SECONDS]: up to SECONDS (default 30) for a line matching PATTERN to appear
# in FILE (a TCG guest starts programs slowly).
wait_for() {
  for _ in $(seq $((${3:-30} * 10))); do grep -q "$2" "$1" 2>/dev/null && return 0; sleep 0.1; done
  echo "no line matching '$2' in $1 after ${3:-30} s; its last line: $(tail -n 1 "$1" 2>&1)"
  return 1
}
# stop_daemon PID NAME [SECONDS]: SIGTERM to a daemon the scenario started, then up to SECONDS
# (default 20) for it to exit; its exit status in $stopped_rc. Still running then (a hang in its
# shutdown, seen once in vm.gpio after whiskerd's last line): where each of its threads waits in the
# kernel (state, wait channel, kernel stack) is printed, it is killed, and $stopped_rc is 124.
# running PID: the process exists and has not exited (a child that exited stays a zombie, state Z,
# until it is waited for).
running() {
  local state
  state=$(awk '{print $3}' "/proc/$1/stat" 2>/dev/null)
  [ -n "$state" ] && [ "$state" != Z ]
}
stop_daemon() {
  local pid=$1 name=$2 secs=${3:-20} t
  kill -TERM "$pid" 2>/dev/null
  for _ in $(seq $((secs * 10))); do
    running "$pid" || break
    sleep 0.1
  done
  if running "$pid"; then
    echo "$name (pid $pid) still running $secs s after SIGTERM; its threads:"
    for t in /proc/"$pid"/task/*; do
      echo "  thread $(basename "$t") $(cat "$t/comm") state $(awk '{print $3}' "$t/stat") wchan $(cat "$t/wchan") syscall $(cut -d" " -f1 "$t/syscall")"
      sed 's/^/    /' "$t/stack" 2>/dev/null
    done
    kill -KILL "$pid"
    wait "$pid" 2>/dev/null
    stopped_rc=124
    return
  fi
  wait "$pid"
  stopped_rc=$?
}
# Reading a driver_status_probe output file (KEY=VALUE lines) of the scenario's probes:
# probe_value FILE NAME: the value of NAME.
probe_value() { sed -n "s/^$2=//p" "$1"; }
# probe_has FILE 'NAME=REGEX': NAME's value matches REGEX; else says what it was.
probe_has() {
  grep -Eq "^$2\$" "$1" && return 0
  echo "${2%%=*}=$(probe_value "$1" "${2%%=*}") in $(basename "$1"), expected ${2#*=}"
  return 1
}
# Loopback multicast for LCM udpm:// inside the guest.
setup_lcm_loopback() {
  ip link set lo up
  ip route add 224.0.0.0/4 dev lo
  # Large receive buffers: the checkers take 500 Hz whisker traffic and 600 kB camera frames.
  sysctl -qw net.core.rmem_max=16777216
  export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"
}
setup_vcan() {
  # Module autoloading would run the initramfs's modprobe, not the host's: load explicitly.
  modprobe vcan
  modprobe can_raw
  # vcan hands every frame to the per-CPU input backlog (netdev_max_backlog, 1000 by default) and
  # drops silently beyond it; a stalled emulated CPU followed by a burst must not lose frames.
  sysctl -qw net.core.netdev_max_backlog=100000
  ip link add dev "$1" type vcan
  ip link set "$1" mtu 72
  ip link set "$1" up
}
# whiskerd's config for the gpio scenarios: BASE (whiskerd_vm.yaml) with its lines on gpio-mockup's
# chip A (enable 0, fault 1, e-stop 2) written to FILE.
write_gpio_config() {
  cat "$1" - > "$2" <<'YAML'
gpio:
  enabled: true
  enable_line: gpio-mockup-A-0
  fault_line: gpio-mockup-A-1
  estop_line: gpio-mockup-A-2
YAML
}
