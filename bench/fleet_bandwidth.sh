#!/usr/bin/env bash
# What a mapping node sends a fleet's merger, on the wire: `rostopic bw` on each of its session
# topics (graph, places, map pieces) while a bag is played into it at the recorded rate, with
# the node's own count and its summary line (frames dropped). A benchmark: the rate depends on
# how fast the camera discovers new places. Also the node's tracking latency (p95) and frames
# dropped, with `--merger` while an rgbdmap_merger listens (on the same cores). Starts a roscore
# of its own on a free port; the node runs as /robot1.
#   bash bench/fleet_bandwidth.sh [--build DIR] [--tum FOLDER] [--merger]
# Default input: a lap of the synthetic 8 x 6 m room (`rgbdmap synth`, a camera walking about
# 1.5 m/s: the merger test's robot 1).
set -u
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir="build"
tum=""
with_merger=0
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --tum) tum="$2"; shift 2 ;;
    --merger) with_merger=1; shift ;;
    -h|--help) sed -n 2,10p "$0"; exit 0 ;;
    *) echo "fleet_bandwidth.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac

source "$root/bench/ros_bench_common.sh"
ros_binaries "$build_dir" node tum2bag rgbdmap merger
if [ -z "$tum" ]; then
  tum="$work/walk"
  "$rgbdmap" synth --room 8x6x3 --path walk --frames 360 --seed 1 --out "$tum" >"$work/synth.log" 2>&1 ||
    { cat "$work/synth.log"; exit 1; }
fi
write_bag "$tum" "$work/camera.bag"
start_roscore

log="$work/node.log"
"$node" __ns:=robot1 "_out:=$work/map.pcd" "_stats:=$work/stats.json" >"$log" 2>&1 &
node_pid=$!
if [ "$with_merger" = 1 ]; then
  "$merger" "_robots:=robot1 robot2" "_out:=$work/merged.pcd" >"$work/merger.log" 2>&1 &
  merger_pid=$!
fi
topics="graph places pieces"
for t in $topics; do
  rostopic bw -w 1000 "/robot1/rgbdmap/session/$t" >"$work/bw-$t.log" 2>&1 &
  pids+=($!)
done
rosbag play -q --wait-for-subscribers "$work/camera.bag" --topics /camera/rgb/image_color \
  /camera/depth/image /camera/rgb/camera_info /camera/rgb/image_color:=/robot1/camera/rgb/image_color \
  /camera/depth/image:=/robot1/camera/depth/image \
  /camera/rgb/camera_info:=/robot1/camera/rgb/camera_info >"$work/play.log" 2>&1
wait_for 120 grep -q "camera stopped delivering frames" "$log" || { cat "$log"; exit 1; }
kill -INT "$node_pid"
wait "$node_pid"
sleep 1  # rostopic bw prints once a second
printf '%-28s %s\n' "topic" "rostopic bw (last average over the run)"
for t in $topics; do
  printf '%-28s %s\n' "/robot1/rgbdmap/session/$t" "$(grep -o 'average: [^ ]*' "$work/bw-$t.log" | tail -1)"
done
grep -o 'session stream: .*' "$log"
grep -o 'rgbdmap_node: .*' "$log"
python3 -c 'import json,sys; t=json.load(open(sys.argv[1]))["latency"]["track"]; print("tracking: p95 %.1f ms, max %.1f ms (%d frames)" % (t["p95_ms"], t["max_ms"], t["count"]))' "$work/stats.json"
if [ "$with_merger" = 1 ]; then
  kill -INT "$merger_pid"
  wait "$merger_pid"
  grep -o 'merger: saved .*' "$work/merger.log" | sed "s|$work/||g"
fi
