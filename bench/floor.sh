#!/usr/bin/env bash
# A building mapped as a user maps one: an office floor rendered by `rgbdmap synth --building`
# (rooms off a corridor, the camera touring every room), mapped with the default configuration
# (odometry and loops) at the camera's rate, or losslessly with --rate max. Prints a row each
# time the camera has walked through another 100 m^2 of floor (cells of 1 m^2 within 1.5 m of
# its path, by the ground truth): the peak RSS so far, the bytes on disk (the map's folder and
# the run's scratch files), each loop's correction that ended in the row (its kind, keyframes
# and seconds) and the slowest checkpoint; then the run's tracking p50/p95, frames dropped and
# how fast it ran against the camera. Samples the run every half second (RSS from /proc, the
# camera's progress from the trajectory it streams). A benchmark: times depend on the machine.
#   bash bench/floor.sh [--build DIR] [--size 30x20] [--seed N] [--fps F] [--rate 1|max]
#                       [--tum FOLDER] [--keep DIR] [-- rgbdmap options...]
# Default: a 30 x 20 m floor, seed 7, 10 fps, --rate 1. Rendering takes a while (a few frames a
# second); --tum maps a floor rendered before (its ground truth gives the area walked).
set -u
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir="build"
size="30x20"
seed=7
fps=10
rate=1
tum=""
keep=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --size) size="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --fps) fps="$2"; shift 2 ;;
    --rate) rate="$2"; shift 2 ;;
    --tum) tum="$2"; shift 2 ;;
    --keep) keep="$2"; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n 2,15p "$0"; exit 0 ;;
    *) echo "floor.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac
rgbdmap="$build_dir/rgbdmap"
[ -x "$rgbdmap" ] || { echo "floor.sh: $rgbdmap not found; build first" >&2; exit 1; }
python=/usr/bin/python3
[ -x "$python" ] || { echo "floor.sh: $python not found (scripts/setup.sh --bench)" >&2; exit 1; }

work=$(mktemp -d "${TMPDIR:-/tmp}/rgbdmap-floor-XXXXXX")
[ -n "$keep" ] || trap 'rm -rf "$work"' EXIT
[ -n "$keep" ] && { mkdir -p "$keep"; work=$(cd "$keep" && pwd); }
if [ -z "$tum" ]; then
  tum="$work/floor"
  echo "rendering a ${size} m floor (seed $seed, $fps fps) into $tum ..."
  "$rgbdmap" synth --building "$size" --seed "$seed" --path tour --fps "$fps" --out "$tum" \
    >"$work/synth.log" 2>&1 || { cat "$work/synth.log"; exit 1; }
  tail -n 3 "$work/synth.log" | head -n 1
fi
[ -f "$tum/groundtruth.txt" ] || { echo "floor.sh: $tum has no groundtruth.txt" >&2; exit 1; }

out="$work/map"
mkdir -p "$out"
samples="$work/samples.txt"
: >"$samples"
start=$(date +%s.%N)
# Odometry, as a camera without ground truth maps (a TUM folder's ground truth would be used).
"$rgbdmap" --source "tum:$tum" --rate "$rate" --out "$out/map.pcd" --no-render --viewer none \
  --set pose.source=odometry --stats "$out/stats.json" "${extra[@]}" >"$work/run.log" 2>&1 &
pid=$!
# Every half second: wall time, the newest frame's timestamp, RSS (kB), bytes on disk (the
# output folder, and the scratch files the run holds open after unlinking them).
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null)
  scratch=0
  for fd in /proc/$pid/fd/*; do
    case "$(readlink "$fd" 2>/dev/null)" in
      *rgbdmap-scratch-*) scratch=$((scratch + $(stat -L -c %s "$fd" 2>/dev/null || echo 0))) ;;
    esac
  done
  folder=$(du -sb "$out" 2>/dev/null | cut -f1)
  frame=$(tail -n 1 "$out/map_trajectory.txt" 2>/dev/null | awk '{print $1}')
  echo "$(date +%s.%N) ${frame:-0} ${rss:-0} $((${folder:-0} + scratch))" >>"$samples"
  sleep 0.5
done
wait "$pid"
status=$?
end=$(date +%s.%N)
[ "$status" -eq 0 ] || { echo "floor.sh: rgbdmap exited with $status"; tail -n 20 "$work/run.log"; exit 1; }

"$python" - "$tum/groundtruth.txt" "$samples" "$work/run.log" "$out/stats.json" "$start" "$end" <<'EOF'
import bisect, datetime, json, math, re, sys

truth_path, samples_path, log_path, stats_path, start, end = sys.argv[1:7]
start, end = float(start), float(end)

# The area walked by each ground-truth time: 1 m^2 cells within 1.5 m of the camera so far.
times, areas, cells = [], [], set()
for line in open(truth_path):
    if line.startswith('#') or not line.strip():
        continue
    t, x, y = (float(v) for v in line.split()[:3])
    for i in range(math.floor(x - 1.5), math.floor(x + 1.5) + 1):
        for j in range(math.floor(y - 1.5), math.floor(y + 1.5) + 1):
            if (i + 0.5 - x) ** 2 + (j + 0.5 - y) ** 2 <= 1.5 ** 2:
                cells.add((i, j))
    times.append(t)
    areas.append(len(cells))

def area_at(t):
    k = bisect.bisect_right(times, t) - 1
    return areas[max(k, 0)] if t > 0 else 0

samples = []  # (wall, area, rss MB, disk MB)
for line in open(samples_path):
    wall, frame, rss, disk = line.split()
    samples.append((float(wall), area_at(float(frame)), int(rss) / 1024, int(disk) / 2**20))

def row_of(area):
    return int(area // 100)

def sample_at(wall):
    k = bisect.bisect_right([s[0] for s in samples], wall) - 1
    return samples[max(k, 0)]

# Log lines: "[2026-11-28 12:56:13.871] [info] ..." in local time.
stamp = re.compile(r'^\[(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d+)\] \[\w+\] (.*)$')
events = {}  # row -> {'loops': [...], 'checkpoint': seconds}
for line in open(log_path, errors='replace'):
    m = stamp.match(line)
    if not m:
        continue
    wall = datetime.datetime.strptime(m.group(1), '%Y-%m-%d %H:%M:%S.%f').timestamp()
    text = m.group(2)
    row = events.setdefault(row_of(sample_at(wall)[1]), {'loops': [], 'checkpoint': 0.0})
    loop = re.match(r'the map follows a loop: (all (\d+) kept keyframes|(\d+) of (\d+) kept '
                    r'keyframes) fused again.* in ([\d.]+) s', text)
    if loop:
        if loop.group(2):
            row['loops'].append('whole %s: %s s' % (loop.group(2), loop.group(5)))
        else:
            row['loops'].append('region %s/%s: %s s' % (loop.group(3), loop.group(4), loop.group(5)))
    # "checkpoint: N points written to MAP.pcd in S s" or "checkpoint: N points, ... to MAP.store in S s"
    checkpoint = re.match(r'checkpoint: \d+ points.* to .* in ([\d.]+) s', text)
    if checkpoint:
        row['checkpoint'] = max(row['checkpoint'], float(checkpoint.group(1)))

print()
print('| walked (m^2) | peak RSS (MB) | on disk (MB) | loop corrections (kind keyframes: time) '
      '| slowest checkpoint (s) |')
print('| --- | --- | --- | --- | --- |')
peak = 0.0
rows = max([row_of(s[1]) for s in samples] + list(events) + [0])
for row in range(rows + 1):
    in_row = [s for s in samples if row_of(s[1]) == row]
    if not in_row and row not in events:
        continue
    peak = max([peak] + [s[2] for s in in_row])
    disk = in_row[-1][3] if in_row else 0.0
    e = events.get(row, {'loops': [], 'checkpoint': 0.0})
    print('| %d-%d | %.0f | %.0f | %s | %s |' % (
        row * 100, row * 100 + 100, peak, disk, '; '.join(e['loops']) or '-',
        '%.2f' % e['checkpoint'] if e['checkpoint'] else '-'))

stats = json.load(open(stats_path))
track = stats.get('latency', {}).get('track', {})
frames = stats.get('frames_processed', 0)
camera_seconds = (times[-1] - times[0]) if times else 0.0
print()
print('walked %d m^2; %d frames, %d dropped; tracking p50 %.1f ms, p95 %.1f ms; peak RSS %.0f MB; '
      '%.0f s for %.0f s of camera (%.2fx real time)' % (
          areas[-1] if areas else 0, frames, stats.get('frames_dropped', 0),
          track.get('p50_ms', float('nan')), track.get('p95_ms', float('nan')),
          stats.get('peak_rss_mb', 0), end - start, camera_seconds,
          camera_seconds / (end - start) if end > start else 0))
EOF
