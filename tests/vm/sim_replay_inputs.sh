#!/bin/bash
# Host side of the VM scenario sim_replay (a ctest fixture): vita-sim writes, once, 2 simulated
# seconds as an LCM log, the CAN FD and classic candump logs of the same run, and a log of the same
# run with another seed (the checker's negative control), plus the world and the classic whiskerd
# config they used. The guest reads them over the read-only host mount: simulating inside the TCG
# guest would cost ~30 s.
#   sim_replay_inputs.sh VITA_SIM SOURCE_DIR WHISKERD_CONFIG OUT_DIR
set -euo pipefail
VITA_SIM=$1
SRC=$2
CONFIG=$3
OUT=$4
rm -rf "$OUT"
mkdir -p "$OUT"
# The arena started where the robot passes box_north within 2 s: contacts and saturated deflections.
sed 's/start_angle_deg: .*/start_angle_deg: 84/' "$SRC/config/worlds/aliased_arena.yaml" > "$OUT/contact_world.yaml"
grep -q 'start_angle_deg: 84' "$OUT/contact_world.yaml"
cp "$CONFIG" "$OUT/whiskerd_fd.yaml"
sed 's/^can:$/can:\n  mode: classic/' "$CONFIG" > "$OUT/whiskerd_classic.yaml"
grep -q '^  mode: classic' "$OUT/whiskerd_classic.yaml"
# The candump logs name the head's bus can0, as a recording on the robot would; the guest maps it.
sim=("$VITA_SIM" --world "$OUT/contact_world.yaml" --robot "$SRC/config/robot.yaml" --duration 2 --can-interface can0 -q)
"${sim[@]}" --seed 11 --whiskerd-config "$OUT/whiskerd_fd.yaml" -o "$OUT/sim.lcmlog" --candump "$OUT/sim_fd.candump"
"${sim[@]}" --seed 11 --whiskerd-config "$OUT/whiskerd_classic.yaml" --candump "$OUT/sim_classic.candump"
"${sim[@]}" --seed 12 -o "$OUT/control.lcmlog"
