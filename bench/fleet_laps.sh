#!/usr/bin/env bash
# Two robots, one lap each, against one run over both laps: the synthetic walk twice round the
# 8 x 6 m room (`rgbdmap synth --path walk --frames 900 --loop-seconds 15`), robot 1 playing
# the first lap into its node, robot 2 the second, at the same time and at half the recorded rate
# (two nodes and the merger share the machine's cores), rgbdmap_merger with
# `_robots:="robot1 robot2"`. Prints, beside one lossless run over both laps (`rgbdmap --rate
# max`, odometry + loops) in the same invocation:
#   - the graph ATE of the merged session's keyframes (MERGED_keyframes.txt) and its ratio to
#     the one run's keyframes';
#   - the merged map's precision and recall at 1 cm, aligned by that graph;
#   - what each node sent the merger (its "session stream" line: KB/s) and frames dropped;
#   - the merger's CPU time (user + system) per robot and per second of camera.
# A benchmark: how many frames a node drops depends on the machine and its load.
# Starts a roscore of its own on a free port.
# --keep DIR: the work folder (sequences, bags, logs, maps, sessions) copied to DIR at the end.
#   bash bench/fleet_laps.sh [--build DIR] [--rate R] [--seed S] [--keep DIR]
set -u
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir="build"
rate=0.5
seed=1
keep=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --rate) rate="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --keep) keep="$2"; shift 2 ;;
    -h|--help) sed -n 2,16p "$0"; exit 0 ;;
    *) echo "fleet_laps.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac

source "$root/bench/ros_bench_common.sh"
ros_binaries "$build_dir" node tum2bag rgbdmap merger
walk="$work/walk"
frames=900
"$rgbdmap" synth --room 8x6x3 --path walk --frames "$frames" --loop-seconds 15 --seed "$seed" \
  --out "$walk" >"$work/synth.log" 2>&1 || { cat "$work/synth.log"; exit 1; }
# lap N: the frames of the Nth half, the images linked.
lap() {
  mkdir -p "$work/lap$1"
  for list in rgb.txt depth.txt; do
    awk -v first="$2" -v last="$3" '/^#/ || NF == 0 { print; next } { n++ } n > first && n <= last' \
      "$walk/$list" >"$work/lap$1/$list"
  done
  cp "$walk/groundtruth.txt" "$work/lap$1/"
  ln -s "$walk/rgb" "$walk/depth" "$work/lap$1/"
  write_bag "$work/lap$1" "$work/robot$1.bag"
}
lap 1 0 $((frames / 2))
lap 2 $((frames / 2)) "$frames"

ate() {  # ESTIMATE: the ATE's RMSE in cm
  "$rgbdmap" evaluate trajectory --estimate "$1" --groundtruth "$walk/groundtruth.txt" \
    --json "$1.json" >/dev/null 2>&1 &&
    python3 -c 'import json,sys; print("%.3f" % (100 * json.load(open(sys.argv[1]))["ate_rmse_m"]))' "$1.json" ||
    echo "nan"
}
score() {  # MAP TRAJECTORY
  "$rgbdmap" evaluate map "$1" --scene "$walk" --trajectory "$2" --json "$1.json" >/dev/null 2>&1 &&
    python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print("precision %.4f, recall %.4f" % (s["precision"], s["recall"]))' "$1.json" ||
    echo "not evaluated"
}

# One run over both laps.
"$rgbdmap" -s "tum:$walk" -o "$work/one.pcd" --rate max --no-render --viewer none -q \
  --set pose.source=odometry >"$work/one.log" 2>&1 || { cat "$work/one.log"; exit 1; }
"$rgbdmap" session "$work/one.session" --trajectory "$work/one_keyframes.txt" >/dev/null 2>&1

start_roscore
"$merger" "_robots:=robot1 robot2" "_out:=$work/merged.pcd" >"$work/merger.log" 2>&1 &
merger_pid=$!
pids+=("$merger_pid")
node_pids=()
for r in robot1 robot2; do
  mkdir -p "$work/$r"
  "$node" __ns:=$r "_map_frame:=$r/map" "_out:=$work/$r/map.pcd" "_stats:=$work/$r/stats.json" \
    >"$work/$r/node.log" 2>&1 &
  node_pids+=($!)
  pids+=($!)
done
started=$SECONDS
player_pids=()
for r in robot1 robot2; do
  rosbag play -q --wait-for-subscribers -r "$rate" --prefix="/$r" "$work/$r.bag" \
    --topics /camera/rgb/image_color /camera/depth/image /camera/rgb/camera_info \
    >"$work/$r/play.log" 2>&1 &
  player_pids+=($!)
done
for pid in "${player_pids[@]}"; do wait "$pid"; done
played=$((SECONDS - started))
for r in robot1 robot2; do
  wait_for 120 grep -q "camera stopped delivering frames" "$work/$r/node.log" ||
    { cat "$work/$r/node.log"; exit 1; }
done
for pid in "${node_pids[@]}"; do kill -INT "$pid"; done
for pid in "${node_pids[@]}"; do wait "$pid"; done
rosservice call /rgbdmap_merger/save_map >/dev/null
# The merger's CPU time so far (clock ticks of user + system time, /proc/PID/stat fields 14, 15).
cpu=$(awk -v hz="$(getconf CLK_TCK)" '{ printf "%.1f", ($14 + $15) / hz }' "/proc/$merger_pid/stat")
kill -INT "$merger_pid"
wait "$merger_pid"

camera_seconds=$(awk -v f="$frames" 'BEGIN { printf "%.0f", f / 30 }')
one=$(ate "$work/one_keyframes.txt")
merged=$(ate "$work/merged_keyframes.txt")
echo "walk twice round 8 x 6 m (seed $seed, $frames frames, ${camera_seconds} s), a lap per robot at rate $rate: played in $played s"
printf '%-34s %s\n' "one run, graph ATE (cm)" "$one"
printf '%-34s %s (%sx one run)\n' "merged graph ATE (cm)" "$merged" \
  "$(awk -v a="$merged" -v b="$one" 'BEGIN { printf "%.2f", a / b }')"
printf '%-34s %s\n' "one run's map" "$(score "$work/one.pcd" "$work/one_keyframes.txt")"
printf '%-34s %s\n' "merged map" "$(score "$work/merged.pcd" "$work/merged_keyframes.txt")"
for r in robot1 robot2; do
  printf '%-34s %s\n' "$r sent" "$(grep -o 'session stream: .*' "$work/$r/node.log" | tail -1)"
  printf '%-34s %s\n' "$r" "$(grep -o 'rgbdmap_node: .*' "$work/$r/node.log")"
done
grep -o 'merger: /robot2 placed.*\|merger: /robot2 not placed.*' "$work/merger.log" | sort -u
printf '%-34s %s s (%s s per robot, %s s per robot and camera second)\n' "merger CPU" "$cpu" \
  "$(awk -v c="$cpu" 'BEGIN { printf "%.1f", c / 2 }')" \
  "$(awk -v c="$cpu" -v s="$camera_seconds" 'BEGIN { printf "%.3f", c / 2 / (s / 2) }')"
if [ -n "$keep" ]; then mkdir -p "$keep" && cp -a "$work/." "$keep/"; fi
