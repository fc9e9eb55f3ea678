#!/usr/bin/env bash
# Memory per lap of a long walk (not CI): does memory follow space, not time? Maps SEQUENCE
# (e.g. `rgbdmap synth -o walk --path walk --room 8x6x2.8 --frames 18000 --loop-seconds 20`:
# 30 laps of 600 frames) and samples the process's RSS every second against the frames read
# (from the status line, logged every 5 s); prints, per lap, the highest RSS seen in it and its
# growth since lap 2, the median and the lowest RSS of the lap and their growth (a checkpoint or
# a pass's end decides the highest; the lowest is the footprint between them), and the map's and
# the place database's memory at the lap's last status line, then the run's stats (peak RSS, map
# and kept-keyframe memory, re-fusions).
#
#   bash bench/laps.sh SEQUENCE FRAMES_PER_LAP [--build build] [-- extra rgbdmap args]
# e.g. bash bench/laps.sh /tmp/walk 600 -- --rate 1     (or --rate max)
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { echo "usage: bash bench/laps.sh SEQUENCE FRAMES_PER_LAP [--build DIR] [-- ARGS]" >&2; exit 2; }
sequence=$1 lap=$2; shift 2
build_dir=build
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir=$2; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "laps.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
out=$(mktemp -d)
"$build_dir/rgbdmap" --source "tum:$sequence" --out "$out/map.pcd" --no-render \
  --viewer none --set pose.source=odometry --stats "$out/stats.json" "${extra[@]}" \
  > "$out/log.txt" 2>&1 &
pid=$!
: > "$out/samples.txt"
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  status=$( (grep 'frames [0-9]* read' "$out/log.txt" || true) | tail -1)
  frames=$(echo "$status" | sed -n 's/.*frames \([0-9]*\) read.*/\1/p')
  map_mb=$(echo "$status" | sed -n 's/.* points, \([0-9.]*\) MB.*/\1/p')
  places_mb=$(echo "$status" | sed -n 's/.*places \([0-9.]*\) MB.*/\1/p')
  [ -n "$rss" ] && echo "${frames:-0} $rss ${map_mb:--} ${places_mb:--}" >> "$out/samples.txt"
  sleep 1
done
wait "$pid" || { echo "laps.sh: rgbdmap failed, see $out/log.txt" >&2; exit 1; }
awk -v lap="$lap" '
  {
    l = int($1 / lap) + 1; if ($2 > peak[l]) peak[l] = $2; if (l > laps) laps = l
    if (!(l in low) || $2 < low[l]) low[l] = $2
    n[l]++; rss[l, n[l]] = $2; map[l] = $3; places[l] = $4
  }
  function median(l,    i, j, t, c, v) {
    c = n[l]; for (i = 1; i <= c; ++i) v[i] = rss[l, i]
    for (i = 2; i <= c; ++i) for (j = i; j > 1 && v[j] < v[j - 1]; --j) { t = v[j]; v[j] = v[j - 1]; v[j - 1] = t }
    return v[int((c + 1) / 2)]
  }
  END {
    print "| lap | highest RSS MB | growth since lap 2 MB | median RSS MB | growth since lap 2 MB | lowest RSS MB | growth since lap 2 MB | map MB | places MB |"
    print "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    if (2 in peak) median2 = median(2)
    for (l = 1; l <= laps; ++l)
      if (l in peak) {
        m = median(l)
        printf "| %d | %.0f | %s | %.0f | %s | %.0f | %s | %s | %s |\n", l, peak[l] / 1024,
          (l >= 2 && 2 in peak) ? sprintf("%+.0f", (peak[l] - peak[2]) / 1024) : "", m / 1024,
          (l >= 2 && 2 in peak) ? sprintf("%+.0f", (m - median2) / 1024) : "", low[l] / 1024,
          (l >= 2 && 2 in peak) ? sprintf("%+.0f", (low[l] - low[2]) / 1024) : "", map[l], places[l]
      }
  }' "$out/samples.txt"
grep -o '"peak_rss_mb": [0-9.]*\|"map_memory_mb": [0-9.]*\|"kept_keyframes_mb": [0-9.]*\|"place_database_mb": [0-9.]*\|"map_refusions": [0-9]*\|"keyframes": [0-9]*\|"loops_accepted": [0-9]*\|"frames_dropped": [0-9]*' "$out/stats.json" | tr '\n' ' '
echo
echo "outputs in $out"
