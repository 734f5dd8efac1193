#!/usr/bin/env bash
# The real frames of ../shared/data through PCL 1.13's pipeline and viewpose's, in one process, frame by
# frame (make bench-pcl, after the simulated frames): PCL's milk scene against the carton scanned from
# it, mOSD frames against eight HOPE objects that are not in them, and real YCB-Video frames against
# their seven objects. PCL takes seconds a frame; about 5 minutes in all on two cores.
# Usage: scripts/bench-pcl-real.sh BUILD_DIR JSON
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:?build directory}
J=${2:?json file}
SHARED=${VIEWPOSE_SHARED_DIR:-../shared}
D=$SHARED/data
if [ ! -d "$D" ]; then
  echo "bench-pcl: $D not found; the real frames are skipped (the simulated ones above are done)"
  exit 0
fi
W=$B/pcl-real
mkdir -p "$W"
V=$B/viewpose
P=$B/viewpose_pcl_bench
[ -f "$W/milk.vpdb" ] || $V db add-view "$D/pcl_kinect/milk.pcd" --object milk --db "$W/milk.vpdb" > /dev/null
# The eight HOPE objects make results uses against mOSD (scripts/results_real.py, HOPE_NEGATIVES).
H=$D/hope_models
[ -f "$W/hope8.vpdb" ] || $V db build "$H/obj_000001.ply" "$H/obj_000002.ply" "$H/obj_000006.ply" "$H/obj_000011.ply" \
  "$H/obj_000013.ply" "$H/obj_000014.ply" "$H/obj_000016.ply" "$H/obj_000017.ply" --unit mm -o "$W/hope8.vpdb" > /dev/null
[ -f "$W/ycbv_dev.vpdb" ] || $V db build --bop-models "$D/ycbv_real_dev/models" --unit mm -o "$W/ycbv_dev.vpdb" > /dev/null
$P --db "$W/milk.vpdb" --scene "$D/pcl_kinect/milk_cartoon_all_small_clorox.pcd" --json "$J"
$P --db "$W/hope8.vpdb" --scene "$D/pcl_mosd/test/test0.pcd" --scene "$D/pcl_mosd/test/test25.pcd" --scene "$D/pcl_mosd/test/test55.pcd" --json "$J"
$P --db "$W/ycbv_dev.vpdb" --camera "$D/ycbv_real_dev/camera.json" --depth-scale 0.1 \
   --scene "$D/ycbv_real_dev/test/000000/depth/000005.png" --scene "$D/ycbv_real_dev/test/000014/depth/000002.png" --json "$J"
