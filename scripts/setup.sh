#!/usr/bin/env bash
# Installs every Debian package rgbdmap needs to build, test and render maps.
# Run as root (CI does); uses sudo when it is available and we are not root.
#   bash scripts/setup.sh [--bench]   (--bench: also what bench/ scripts compare with: Open3D as
#                                      a peer, and ../shared/tools/map_thickness.py's needs)
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git
  libpcl-dev libopencv-dev libopencv-contrib-dev libeigen3-dev
  libopenni2-dev libfreenect-dev libusb-1.0-0-dev libyaml-cpp-dev libcli11-dev libspdlog-dev
  libboost-dev libgtest-dev libgmock-dev libbenchmark-dev libopenmpi-dev
  libtsl-hopscotch-map-dev libceres-dev libdeflate-dev liboctomap-dev octomap-tools
  libvtk9-dev libx11-dev libgl-dev xvfb ccache
  # ROS 1 Noetic as Debian packages it: the ros/ adapter (rosbag: source, rgbdmap_node) and the
  # tools its tests drive (roscore, rosbag, rostopic).
  ros-core-dev libroscpp-dev librosbag-dev libsensor-msgs-dev libgeometry-msgs-dev
  libstd-srvs-dev libtf2-ros-dev ros-core python3-rosbag python3-rostopic
  python3-sensor-msgs python3-geometry-msgs python3-std-srvs libnav-msgs-dev python3-nav-msgs
  python3-tf2-ros
)
if [ "${1:-}" = "--bench" ]; then packages+=(python3-open3d python3-scipy); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends "${missing[@]}"
