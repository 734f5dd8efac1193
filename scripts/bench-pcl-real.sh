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
# The eight HOPE objects make results uses against mOSD: one list, scripts/results_real.py's HOPE_NEGATIVES.
H=$D/hope_models
HOPE_FILES=$(python3 -c 'import sys; sys.path.insert(0, "scripts"); from results_real import HOPE_NEGATIVES as n
print(" ".join(f"obj_{i:06d}.ply" for i in n))')
if [ ! -f "$W/hope8.vpdb" ]; then
  hope=()
  for f in $HOPE_FILES; do hope+=("$H/$f"); done
  $V db build "${hope[@]}" --unit mm -o "$W/hope8.vpdb" > /dev/null
fi
[ -f "$W/ycbv_dev.vpdb" ] || $V db build --bop-models "$D/ycbv_real_dev/models" --unit mm -o "$W/ycbv_dev.vpdb" > /dev/null
$P --db "$W/milk.vpdb" --scene "$D/pcl_kinect/milk_cartoon_all_small_clorox.pcd" --json "$J"
$P --db "$W/hope8.vpdb" --scene "$D/pcl_mosd/test/test0.pcd" --scene "$D/pcl_mosd/test/test25.pcd" --scene "$D/pcl_mosd/test/test55.pcd" --json "$J"
$P --db "$W/ycbv_dev.vpdb" --camera "$D/ycbv_real_dev/camera.json" --depth-scale 0.1 \
   --scene "$D/ycbv_real_dev/test/000000/depth/000005.png" --scene "$D/ycbv_real_dev/test/000014/depth/000002.png" --json "$J"
