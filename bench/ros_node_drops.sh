#!/usr/bin/env bash
# Frames the ROS node drops when a bag is played at the recorded rate, as a live camera would
# send them: a benchmark, since it depends on the machine and its load (the node's tests check
# only that every frame is accounted for). Starts a roscore of its own on a free port, the node,
# and `rosbag play` of a bag written from a TUM folder; prints the node's summary line (images
# received, pairs, dropped, mapped) for each run.
#   bash bench/ros_node_drops.sh [--build DIR] [--runs N] [--tum FOLDER]
set -u
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir="build"
runs=3
tum="${RGBDMAP_DATA_DIR:-$root/../shared/data}/tum/rgbd_dataset_freiburg1_rpy_head100"
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --tum) tum="$2"; shift 2 ;;
    -h|--help) sed -n 2,7p "$0"; exit 0 ;;
    *) echo "ros_node_drops.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac

source "$root/bench/ros_bench_common.sh"
ros_binaries "$build_dir" node tum2bag
write_bag "$tum" "$work/camera.bag"
start_roscore

for run in $(seq "$runs"); do
  log="$work/node-$run.log"
  "$node" "_out:=$work/map-$run.pcd" >"$log" 2>&1 &
  node_pid=$!
  rosbag play -q --wait-for-subscribers "$work/camera.bag" --topics /camera/rgb/image_color \
    /camera/depth/image /camera/rgb/camera_info >"$work/play-$run.log" 2>&1
  # The node reports the camera silent once it has taken every image played.
  wait_for 60 grep -q "camera stopped delivering frames" "$log" || { cat "$log"; exit 1; }
  kill -INT "$node_pid"
  wait "$node_pid"
  echo "run $run: $(grep -o 'rgbdmap_node: .*' "$log")"
done
