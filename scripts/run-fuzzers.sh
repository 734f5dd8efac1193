#!/usr/bin/env bash
# Runs every libFuzzer target in BUILD_DIR for SECONDS each, starting from the committed seed corpus
# (fuzz/corpus/<target>). New inputs go to BUILD_DIR/fuzz-work, never into the repository. A crash
# stops the run; its input is saved in BUILD_DIR/fuzz-artifacts, to be added to fuzz/regressions.
set -euo pipefail
build=${1:?usage: run-fuzzers.sh BUILD_DIR SECONDS}
seconds=${2:-60}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$build/fuzz-artifacts"
for target in pcd ply depth_png_json view_database; do
  work="$build/fuzz-work/$target"
  mkdir -p "$work"
  echo "fuzz: $target for ${seconds}s"
  if ! "$build/fuzz_$target" "$work" "$root/fuzz/corpus/$target" "$root/fuzz/regressions/$target" \
      -max_total_time="$seconds" -max_len=16384 -timeout=10 -rss_limit_mb=2048 \
      -artifact_prefix="$build/fuzz-artifacts/$target-" -print_final_stats=1 >"$build/fuzz-$target.log" 2>&1; then
    tail -n 40 "$build/fuzz-$target.log"
    echo "fuzz: $target FAILED; the input is in $build/fuzz-artifacts/ (add it to fuzz/regressions/$target)"
    exit 1
  fi
  grep -E "stat::number_of_executed_units|cov:" "$build/fuzz-$target.log" | tail -n 2 | sed "s/^/fuzz: $target: /"
done
echo "fuzz: no crash in any target"
