#!/usr/bin/env bash
# The main job on a fresh machine, no camera and no download: install, build, render a synthetic
# room as a TUM sequence, map it, and write out/map.pcd, a picture of it, out/map.png, and the
# map as a triangle mesh, out/map.ply.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" --target rgbdmap
mkdir -p out
[ -f out/synthetic_room/groundtruth.txt ] || ./build/rgbdmap synth --out out/synthetic_room
./build/rgbdmap --source tum:out/synthetic_room --out out/map.pcd --mesh out/map.ply --rate max \
  --stats out/stats.json
./build/rgbdmap evaluate map out/map.pcd --scene out/synthetic_room
echo "map: out/map.pcd  mesh: out/map.ply  picture: out/map.png  keyframes: out/map_keyframes.txt"
