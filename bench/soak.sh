#!/usr/bin/env bash
# Soak test (not part of CI): a looping replay through the OpenNI2 TUM driver at the recorded
# rate, as a live camera, for --minutes (30 by default), with a checkpoint every 30 s and a
# SIGUSR1 every --usr1 seconds. Every --sample seconds it records RSS, open file descriptors and
# threads, and checks that the map on disk (the last checkpoint) loads. Fails when descriptors or
# threads grow after the first sample (taken after the first loops), when RSS grows by more than
# 20% + 20 MB over it, when a checkpoint does not load, or when the run does not end with exit 0
# on SIGINT.
#
#   bash bench/soak.sh [--minutes 30] [--usr1 3] [--sample 60] [--build build] [--sequence DIR]
#                      [--motion still|loop]
# --motion still (default) plays the sequence's first pair over and over, every frame fused: the
# map cannot grow, so growth is a leak. loop plays the sequence looped: odometry drifts at each
# jump from its last frame back to its first, so the map (and memory) grows with the drift.
#
# Needs the build's rgbdmap and OpenNI2 TUM driver runtime:
#   cmake --build build --target rgbdmap openni2_tum_runtime
set -u
cd "$(dirname "$0")/.."
minutes=30
usr1=3
sample=60
build_dir=build
sequence=../shared/data/tum/rgbd_dataset_freiburg1_xyz
motion=still
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) minutes="$2"; shift 2 ;;
    --usr1) usr1="$2"; shift 2 ;;
    --sample) sample="$2"; shift 2 ;;
    --build) build_dir="$2"; shift 2 ;;
    --sequence) sequence="$2"; shift 2 ;;
    --motion) motion="$2"; shift 2 ;;
    -h|--help) sed -n 2,17p "$0"; exit 0 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
rgbdmap="$build_dir/rgbdmap"
runtime="$(cd "$build_dir" && pwd)/openni2"
[ -x "$rgbdmap" ] || { echo "soak.sh: $rgbdmap is missing (build the rgbdmap target)" >&2; exit 2; }
[ -f "$runtime/OpenNI2/Drivers/libTumDevice.so.0" ] || {
  echo "soak.sh: $runtime has no TUM driver (build the openni2_tum_runtime target)" >&2; exit 2; }
sequence=$(cd "$sequence" && pwd) || exit 2

work=$(mktemp -d "${TMPDIR:-/tmp}/rgbdmap-soak.XXXXXX") || exit 2
keyframes=()
case "$motion" in
  still)
    # The sequence's first pair, 30 times: a camera held still, every frame fused. The map
    # cannot grow, so memory that does is a leak.
    still="$work/still/${sequence##*/}"
    mkdir -p "$still"
    ln -s "$sequence/rgb" "$still/rgb"
    ln -s "$sequence/depth" "$still/depth"
    for list in rgb depth; do
      first=$(awk '$1 !~ /^#/ && NF >= 2 {print $2; exit}' "$sequence/$list.txt")
      awk -v f="$first" 'BEGIN {for (i = 0; i < 30; i++) printf "%.6f %s\n", 1000 + i / 30, f}' \
        >"$still/$list.txt"
    done
    sequence="$still"
    keyframes=(--set keyframe.policy=interval --set keyframe.every_n=1)
    ;;
  loop)
    # The sequence looped as it is: odometry cannot tell the jump from its last frame to its
    # first from motion, drifts a little at each, and the map grows; this measures that drift,
    # so memory growth here is not a leak.
    ;;
  *) echo "soak.sh: --motion is still or loop" >&2; exit 2 ;;
esac
echo "soak: $minutes min of openni2:tum:$sequence?loop=1 ($motion), SIGUSR1 every $usr1 s, samples every $sample s in $work"
LD_LIBRARY_PATH="$runtime" "$rgbdmap" --source "openni2:tum:$sequence?loop=1" --out "$work/map.pcd" \
  --set checkpoint.every_seconds=30 --set checkpoint.every_keyframes=0 --stats "$work/stats.json" \
  "${keyframes[@]}" -q --no-render >"$work/log.txt" 2>&1 &
pid=$!

failed=0
fail() { echo "FAIL: $*"; failed=1; }
status_field() { awk -v k="$1:" '$1 == k {print $2}' "/proc/$pid/status"; }

start=$(date +%s)
end=$((start + minutes * 60))
next_sample=$((start + sample))
samples=0
base_rss=0 base_fds=0 base_threads=0
printf '%8s %10s %6s %8s %12s %s\n' minute rss_mb fds threads map_points checkpoint
while [ "$(date +%s)" -lt "$end" ]; do
  kill -0 "$pid" 2>/dev/null || { fail "rgbdmap ended early"; break; }
  kill -USR1 "$pid"
  sleep "$usr1"
  now=$(date +%s)
  [ "$now" -lt "$next_sample" ] && continue
  next_sample=$((next_sample + sample))
  rss_kb=$(status_field VmRSS)
  threads=$(status_field Threads)
  # The fewest of a few looks: a checkpoint being written or an image being read holds one
  # more for a moment.
  fds=$(for _ in 1 2 3 4 5; do ls "/proc/$pid/fd" | wc -l; sleep 0.1; done | sort -n | head -1)
  rss_mb=$((rss_kb / 1024))
  points=-
  verdict="none yet"
  if [ -f "$work/map.pcd" ]; then
    cp "$work/map.pcd" "$work/checkpoint.pcd"  # the destination is always a complete map
    if "$rgbdmap" render "$work/checkpoint.pcd" --out "$work/checkpoint.png" >"$work/render.log" 2>&1; then
      points=$(awk '$1 == "POINTS" {print $2; exit}' "$work/checkpoint.pcd")
      verdict=loads
    else
      verdict="DOES NOT LOAD"
      fail "checkpoint at minute $(((now - start) / 60)) does not load: $(tail -1 "$work/render.log")"
    fi
  fi
  printf '%8s %10s %6s %8s %12s %s\n' "$(((now - start) / 60))" "$rss_mb" "$fds" "$threads" "$points" "$verdict"
  samples=$((samples + 1))
  if [ "$samples" -eq 1 ]; then
    base_rss=$rss_mb base_fds=$fds base_threads=$threads
  else
    [ "$fds" -gt "$base_fds" ] && fail "open descriptors grew: $base_fds -> $fds"
    [ "$threads" -gt "$base_threads" ] && fail "threads grew: $base_threads -> $threads"
    [ "$rss_mb" -gt $((base_rss * 12 / 10 + 20)) ] && fail "RSS grew: $base_rss MB -> $rss_mb MB"
  fi
done
kill -INT "$pid" 2>/dev/null
wait "$pid"
code=$?
[ "$code" -eq 0 ] || fail "exit code $code after SIGINT: $(tail -3 "$work/log.txt")"
checkpoints=$(grep -c "checkpoint: " "$work/log.txt")
failed_writes=$(grep -c "checkpoint failed" "$work/log.txt")
usr1_seen=$(grep -c "SIGUSR1: writing a checkpoint" "$work/log.txt")
echo "checkpoints written: $checkpoints, failed: $failed_writes, SIGUSR1 taken: $usr1_seen"
[ "$failed_writes" -eq 0 ] || fail "$failed_writes checkpoints failed"
"$rgbdmap" render "$work/map.pcd" --out "$work/map.png" >/dev/null 2>&1 || fail "the final map does not load"
if [ "$failed" -eq 0 ]; then
  echo "soak passed ($minutes min, $samples samples); files in $work"
  rm -f "$work/checkpoint.pcd"
fi
exit $failed
