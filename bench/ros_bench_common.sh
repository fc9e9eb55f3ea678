# Sourced by the ROS benchmarks: the binaries of a build, a work folder removed at exit with the
# processes in `pids`, a roscore of their own on a free port, `wait_for`, and a bag written from
# a TUM folder.
# ros_binaries BUILD_DIR BINARY...: sets node, tum2bag, rgbdmap, merger and play to the build's
# programs, and stops naming the first of those given (by variable name) that is not built.
ros_binaries() {
  local dir=$1 name
  shift
  node="$dir/ros/rgbdmap_node"
  tum2bag="$dir/ros/rgbdmap-tum2bag"
  rgbdmap="$dir/rgbdmap"
  merger="$dir/ros/rgbdmap_merger"
  play="$dir/ros/rgbdmap-play"
  for name in "$@"; do
    [ -x "${!name}" ] || { echo "$(basename "$0"): ${!name} not found; build first" >&2; exit 1; }
  done
}
work=$(mktemp -d)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
# wait_for SECONDS COMMAND...: until the command succeeds (1 when it did not in time).
wait_for() {
  local deadline=$((SECONDS + $1))
  shift
  until "$@"; do
    [ "$SECONDS" -lt "$deadline" ] || return 1
    sleep 0.2
  done
}
# start_roscore: a master on 127.0.0.1 at a free port, for this shell and its children.
start_roscore() {
  local port
  port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_IP=127.0.0.1 ROS_HOME="$work/ros"
  roscore -p "$port" >"$work/roscore.log" 2>&1 &
  pids+=($!)
  wait_for 30 rostopic list >/dev/null 2>&1 || { cat "$work/roscore.log"; exit 1; }
}
# write_bag TUM_FOLDER BAG (rgbdmap-tum2bag at $tum2bag)
write_bag() {
  "$tum2bag" "$1" "$2" >"$work/tum2bag.log" 2>&1 || { cat "$work/tum2bag.log"; exit 1; }
}
