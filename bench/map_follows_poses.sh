#!/usr/bin/env bash
# Does the map follow its poses? Maps SEQUENCE with the defaults (odometry poses, loop closure,
# --rate max), then fuses the same keyframes at their final poses (MAP_keyframes.txt) into one
# TSDF, and compares the two maps with ../shared/tools/map_thickness.py: points, planar share,
# median thickness. A map that left walls written twice has more points, a lower planar share
# and a thicker surface than the re-fused one. Not part of CI.
#
#   bash bench/map_follows_poses.sh SEQUENCE [--build build] [--out DIR] [-- extra rgbdmap args]
# Needs python3-open3d and python3-scipy for the thickness tool: bash scripts/setup.sh --bench.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { echo "usage: bash bench/map_follows_poses.sh SEQUENCE [--build DIR] [--out DIR] [-- ARGS]" >&2; exit 2; }
sequence=$1; shift
build_dir=build
out=$(mktemp -d)
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "map_follows_poses.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
[ -d "$sequence" ] || { echo "map_follows_poses.sh: $sequence: no such folder" >&2; exit 2; }
thickness=../shared/tools/map_thickness.py
/usr/bin/python3 -c 'import open3d, scipy' 2>/dev/null ||
  { echo "map_follows_poses.sh: $thickness needs python3-open3d and python3-scipy (bash scripts/setup.sh --bench)" >&2; exit 2; }
mkdir -p "$out"
bin=$build_dir/rgbdmap
"$bin" --source "tum:$sequence" --out "$out/live.pcd" --rate max -q --no-render \
  --stats "$out/live.json" "${extra[@]}" > "$out/live.log" 2>&1
"$bin" --source "tum:$sequence" --out "$out/refused.pcd" --rate max -q --no-render \
  --set pose.source=trajectory --set pose.trajectory="$out/live_keyframes.txt" \
  --set keyframe.every_n=1 --set pose.max_gap=0.001 --stats "$out/refused.json" \
  > "$out/refused.log" 2>&1
/usr/bin/python3 "$thickness" "$out/live.pcd" --json > "$out/live.thickness.json"
/usr/bin/python3 "$thickness" "$out/refused.pcd" --json > "$out/refused.thickness.json"
/usr/bin/python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
def load(name):
    return json.load(open(f"{out}/{name}.thickness.json")), json.load(open(f"{out}/{name}.json"))
(lt, ls), (rt, rs) = load("live"), load("refused")
print(f"| map | points | planar share | thickness mm | peak RSS MB | map MB | kept keyframes MB | re-fusions |")
print(f"| --- | --- | --- | --- | --- | --- | --- | --- |")
for name, t, s in (("as written (loops on)", lt, ls), ("keyframes re-fused at final poses", rt, rs)):
    print(f"| {name} | {t['points']} | {t['planar_share']:.3f} | {t['thickness_median_mm']:.2f} | "
          f"{s['peak_rss_mb']:.0f} | {s['map_memory_mb']:.1f} | {s.get('kept_keyframes_mb', 0):.1f} | "
          f"{s.get('map_refusions', 0)} |")
print(f"| ratio / difference | {lt['points'] / rt['points']:.2f}x | "
      f"{lt['planar_share'] / rt['planar_share']:.2f}x | "
      f"{lt['thickness_median_mm'] - rt['thickness_median_mm']:+.2f} | | | | |")
PY
echo "outputs in $out"
