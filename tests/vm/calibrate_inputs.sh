#!/bin/bash
# Host side of the VM scenario calibrate (a ctest fixture): vita-sim writes the bring-up sessions of a
# robot with a drawn true calibration (rest, taps, jig, sweep; a rest with a silent board), the true
# calibration as a whiskerd drop-in, and the list of whiskers the taps and the jig touch (0, the two
# swapped ones, the mirrored board's first two, 23: every case in a few seconds of bus time). The
# guest replays them; simulating inside the TCG guest would cost minutes.
#   calibrate_inputs.sh VITA_SIM SOURCE_DIR OUT_DIR
set -euo pipefail
VITA_SIM=$1
SRC=$2
OUT=$3
rm -rf "$OUT"
mkdir -p "$OUT/etc/whiskerd.d"
cp "$SRC/config/whiskerd.yaml" "$OUT/etc/whiskerd.yaml"
sim=("$VITA_SIM" --whiskerd-config "$OUT/etc/whiskerd.yaml" --true-calibration-seed 5 --can-interface can0)
said=$("${sim[@]}" --bringup rest --bringup-duration 3 --candump "$OUT/rest.log" \
       --write-true-calibration "$OUT/truth.yaml" 2>&1)
echo "$said"
# "... whiskers A and B swapped, board M mirrored)"
read -r a b m < <(echo "$said" | sed -n 's/.*whiskers \([0-9]*\) and \([0-9]*\) swapped, board \([0-9]\) mirrored.*/\1 \2 \3/p')
order=$(printf '%s\n' 0 "$a" "$b" $((m * 4)) $((m * 4 + 1)) 23 | awk '!seen[$0]++' | paste -sd,)
echo "$order" > "$OUT/order"
"${sim[@]}" --bringup taps --bringup-order "$order" --candump "$OUT/taps.log" 2> /dev/null
"${sim[@]}" --bringup jig --bringup-order "$order" --candump "$OUT/jig.log" 2> /dev/null
"${sim[@]}" --bringup sweep --candump "$OUT/sweep.log" 2> /dev/null
"${sim[@]}" --bringup rest --bringup-duration 2 --silent-board 2 --candump "$OUT/silent.log" 2> /dev/null
echo "order $order"
