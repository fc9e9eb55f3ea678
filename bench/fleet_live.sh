#!/usr/bin/env bash
# The merger test's fleet at the recorded rate, as cameras would send it: three mapping nodes
# (a lap of the synthetic room, the second half of another lap 15 cm further from the walls, and
# fr1/xyz) and rgbdmap_merger on one master, each bag played into its robot's namespace at once.
# A benchmark: how many frames each node drops, whether robot 2 is placed and how good the maps
# are all depend on the machine and its load (the test, RosMerger.TwoRobots..., plays losslessly
# instead and asserts). Prints each node's summary line (frames dropped), the precision of the
# robots' own maps, the merger's placements and the merged map's score, and the wall time.
# With --lossless the nodes run with ~lossless and rgbdmap-play waits for them, as in the test.
# Starts a roscore of its own on a free port.
#   bash bench/fleet_live.sh [--build DIR] [--lossless]
set -u
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir="build"
lossless=0
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --lossless) lossless=1; shift ;;
    -h|--help) sed -n 2,11p "$0"; exit 0 ;;
    *) echo "fleet_live.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac
xyz="${RGBDMAP_DATA_DIR:-$root/../shared/data}/tum/rgbd_dataset_freiburg1_xyz"

source "$root/bench/ros_bench_common.sh"
ros_binaries "$build_dir" node tum2bag rgbdmap merger play
# The test's walks (tests/test_ros_merger.cpp): robot 2 plays the second lap from frame 180 on.
synth() {
  "$rgbdmap" synth --out "$1" --path walk --frames 360 "${@:2}" >"$work/synth.log" 2>&1 ||
    { cat "$work/synth.log"; exit 1; }
}
synth "$work/lap1" --seed 1
synth "$work/lap2" --seed 2 --path-inset 0.95
mkdir -p "$work/tail2"
for list in rgb.txt depth.txt; do
  awk '/^#/ || NF == 0 { print; next } n++ >= 180' "$work/lap2/$list" >"$work/tail2/$list"
done
cp "$work/lap2/groundtruth.txt" "$work/tail2/"
ln -s "$work/lap2/rgb" "$work/lap2/depth" "$work/tail2/"
write_bag "$work/lap1" "$work/robot1.bag"
write_bag "$work/tail2" "$work/robot2.bag"
write_bag "$xyz" "$work/robot3.bag"
start_roscore

"$merger" "_robots:=[robot1, robot2, robot3]" "_out:=$work/merged.pcd" >"$work/merger.log" 2>&1 &
merger_pid=$!
pids+=("$merger_pid")
node_pids=()
for r in robot1 robot2 robot3; do
  mkdir -p "$work/$r"
  "$node" __ns:=$r "_map_frame:=$r/map" "_out:=$work/$r/map.pcd" "_stats:=$work/$r/stats.json" \
    "_lossless:=$([ "$lossless" = 1 ] && echo true || echo false)" >"$work/$r/node.log" 2>&1 &
  node_pids+=($!)
  pids+=($!)
done
started=$SECONDS
player_pids=()
for r in robot1 robot2 robot3; do
  if [ "$lossless" = 1 ]; then
    player=("$play" --prefix="/$r")
  else
    player=(rosbag play -q --wait-for-subscribers --prefix="/$r")
  fi
  "${player[@]}" "$work/$r.bag" --topics /camera/rgb/image_color /camera/depth/image \
    /camera/rgb/camera_info >"$work/$r/play.log" 2>&1 &
  player_pids+=($!)
done
for pid in "${player_pids[@]}"; do wait "$pid"; done
played=$((SECONDS - started))
for r in robot1 robot2 robot3; do
  wait_for 120 grep -q "camera stopped delivering frames" "$work/$r/node.log" ||
    { cat "$work/$r/node.log"; exit 1; }
done
# Robot 2 is placed once the merger has its places and robot 1's (within seconds), or never.
wait_for 60 grep -q "/robot2 placed" "$work/merger.log" || true
for pid in "${node_pids[@]}"; do kill -INT "$pid"; done
for pid in "${node_pids[@]}"; do wait "$pid"; done
rosservice call /rgbdmap_merger/save_map >/dev/null
kill -INT "$merger_pid"
wait "$merger_pid"

precision() {  # MAP SCENE TRAJECTORY
  "$rgbdmap" evaluate map "$1" --scene "$2" --trajectory "$3" --json "$1.json" >/dev/null 2>&1 &&
    python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print("precision %.4f, recall %.4f" % (s["precision"], s["recall"]))' "$1.json" ||
    echo "not evaluated"
}
echo "players done after $played s (the bags are 12 s, 6 s and 1 s long)$([ "$lossless" = 1 ] && echo ", lossless")"
for r in robot1 robot2 robot3; do
  echo "$r: $(grep -o 'rgbdmap_node: .*' "$work/$r/node.log")"
done
echo "robot1's own map: $(precision "$work/robot1/map.pcd" "$work/lap1" "$work/robot1/map_keyframes.txt")"
echo "robot2's own map: $(precision "$work/robot2/map.pcd" "$work/lap2" "$work/robot2/map_keyframes.txt")"
grep -o 'merger: /robot[0-9] placed.*\|merger: /robot[0-9] not placed.*' "$work/merger.log" | sort -u
# In robot 1's frame, aligned by robot 1's own keyframes (the test aligns by its keyframes in
# the merged graph, which the merge moves a little).
echo "merged map: $(precision "$work/merged.pcd" "$work/lap1" "$work/robot1/map_keyframes.txt")"
