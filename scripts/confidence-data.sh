#!/usr/bin/env bash
# Makes the data the confidence model (src/pose/confidence.cpp) is fit on, and fits it: simulated
# rooms and clutter with the built-in shapes and five HOPE objects, every pose that passes
# verification's bounds heard of (bop --keep-best --hypotheses) and labelled against the ground
# truth; real YCB-Video frames as the check, never fit on. About 25 minutes on two cores.
# Usage: scripts/confidence-data.sh [WORK]   (make confidence; needs a build and ../shared/data)
set -euo pipefail
cd "$(dirname "$0")/.."
V=build/viewpose
W=${1:-build/confidence}
SHARED=${VIEWPOSE_SHARED_DIR:-../shared}
H=$SHARED/data/hope_models
mkdir -p "$W"
[ -d "$H" ] || { echo "confidence-data: $H not found (the HOPE meshes of ../shared/data)"; exit 1; }
$V simulate --preset room --model jug --model box --model can --model mug --images 40 --rooms 8 --seed 101 -o "$W/room_builtin"
$V simulate --preset room --model "$H/obj_000001.ply" --model "$H/obj_000006.ply" --model "$H/obj_000013.ply" \
   --model "$H/obj_000014.ply" --model "$H/obj_000016.ply" --unit mm --images 40 --rooms 8 --seed 102 -o "$W/room_hope"
$V simulate --preset clutter --model jug --model box --model can --model mug --images 30 --seed 103 --room -o "$W/clutter_room"
$V db build jug box can mug -o "$W/builtin.vpdb"
$V db build --bop-models "$W/room_hope/models" --unit mm -o "$W/hope5.vpdb"
$V db build --bop-models "$SHARED/data/ycbv_real_dev/models" --unit mm -o "$W/ycbv_dev.vpdb"
# Every pose verification passes, with the confidence threshold off (--min-score 0): the fit must see them all.
hyp() { $V bop --keep-best --min-score 0 --db "$1" --dataset "$2" -o "$W/$3.csv" --hypotheses "$W/$3.jsonl" "${@:4}"; }
hyp "$W/builtin.vpdb" "$W/room_builtin" room_builtin
hyp "$W/hope5.vpdb" "$W/room_hope" room_hope
hyp "$W/builtin.vpdb" "$W/clutter_room" clutter_room
hyp "$W/ycbv_dev.vpdb" "$SHARED/data/ycbv_real_dev" ycbv_real_dev
/usr/bin/python3 scripts/fit-confidence.py --train "$W/room_builtin.jsonl" "$W/room_hope.jsonl" "$W/clutter_room.jsonl" \
   --check "$W/ycbv_real_dev.jsonl" --json docs/results/confidence_fit.json --plot docs/results/confidence_calibration.png
