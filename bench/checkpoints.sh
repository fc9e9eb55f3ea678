#!/usr/bin/env bash
# What checkpoints write: one sequence mapped twice in the same invocation, with the map store
# (the default: each checkpoint appends the map's changed cells to MAP.store/) and with
# checkpoint.store=false (each checkpoint rewrites MAP.pcd whole). Prints, for each, the
# checkpoints, the bytes the map's checkpoints wrote, the seconds the writer spent on
# checkpoints (all of it: map, trajectories, session), the session's share and the new images
# and places its sessions wrote (each once: images.bin and places.data are appended to), and the
# run's wall time and peak RSS. A benchmark: times depend on the machine; compare the rows.
#   bash bench/checkpoints.sh --tum FOLDER [--build DIR] [--every N] [--keep DIR]
#                             [-- rgbdmap options...]
# Default: a checkpoint every 25 keyframes, --rate max, odometry and loops. For a large space:
#   rgbdmap synth --room 16x12x3 --path walk --frames 1800 --loop-seconds 48 --out room16
#   bash bench/checkpoints.sh --tum room16 -- --set loop.keyframe_memory=16
set -u
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir="build"
tum=""
every=25
keep=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --tum) tum="$2"; shift 2 ;;
    --every) every="$2"; shift 2 ;;
    --keep) keep="$2"; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n 2,13p "$0"; exit 0 ;;
    *) echo "checkpoints.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac
rgbdmap="$build_dir/rgbdmap"
[ -x "$rgbdmap" ] || { echo "checkpoints.sh: $rgbdmap not found; build first" >&2; exit 1; }
[ -n "$tum" ] && [ -f "$tum/groundtruth.txt" ] ||
  { echo "checkpoints.sh: --tum FOLDER (a TUM-layout folder) is required" >&2; exit 2; }
python=/usr/bin/python3
[ -x "$python" ] || { echo "checkpoints.sh: $python not found (scripts/setup.sh --bench)" >&2; exit 1; }

work=$(mktemp -d "${TMPDIR:-/tmp}/rgbdmap-checkpoints-XXXXXX")
[ -n "$keep" ] || trap 'rm -rf "$work"' EXIT
[ -n "$keep" ] && { mkdir -p "$keep"; work=$(cd "$keep" && pwd); }

for mode in store pcd; do
  options=()
  [ "$mode" = pcd ] && options=(--set checkpoint.store=false)
  mkdir -p "$work/$mode"
  "$rgbdmap" --source "tum:$tum" --out "$work/$mode/map.pcd" --rate max --no-render \
    --viewer none -q --set pose.source=odometry --set checkpoint.every_keyframes="$every" \
    --set checkpoint.min_seconds=0 --stats "$work/$mode/stats.json" "${options[@]}" \
    "${extra[@]}" >"$work/$mode/log.txt" 2>&1 ||
    { tail -n 20 "$work/$mode/log.txt"; exit 1; }
done

"$python" - "$work" <<'EOF'
import json, re, sys
work = sys.argv[1]
print('| checkpoints write | checkpoints | map bytes written (MB) | writer seconds (all) |'
      ' of which sessions | new images and places (MB) | wall (s) | peak RSS (MB) |')
print('| --- | --- | --- | --- | --- | --- | --- | --- |')
for mode, label in (('store', 'changes to MAP.store'), ('pcd', 'MAP.pcd whole')):
    log = open(f'{work}/{mode}/log.txt').read()
    stats = json.load(open(f'{work}/{mode}/stats.json'))
    seconds = [float(s) for s in re.findall(r'checkpoint: \d+ points.* in ([\d.]+) s', log)]
    session = [float(s) for s in re.findall(r'session: [\d.]+ MB written to \S+ in ([\d.]+) s', log)]
    images = sum(float(s) for s in re.findall(r'\(([\d.]+) MB of new images and places\)', log))
    if mode == 'store':
        written = stats['store_bytes_written'] / 2**20
    else:  # 16 bytes a point and the header, each PCD
        written = sum(int(n) * 16 + 200 for n in
                      re.findall(r'checkpoint: (\d+) points written to', log)) / 2**20
    print(f'| {label} | {len(seconds)} | {written:.0f} | {sum(seconds):.2f} (max {max(seconds):.2f}) |'
          f' {sum(session):.2f} | {images:.0f} | {stats["wall_seconds"]:.1f} |'
          f' {stats["peak_rss_mb"]:.0f} |')
EOF
