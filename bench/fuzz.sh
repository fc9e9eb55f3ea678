#!/usr/bin/env bash
# Fuzzes every parser of outside input with libFuzzer (not part of CI): TUM lists and ground
# truth, trajectory files, config YAML and --set, the PCD/PLY maps `render` and `evaluate` read,
# the PLY meshes (--mesh) `render` and `view` read, the PNGs of TUM folders (PngDecoder).
# Each target runs for --seconds with ASan + UBSan; any crash, hang, leak or sanitizer report
# fails the run and leaves the input in <build>/crashes/ (turn it into a regression test).
#
#   bash bench/fuzz.sh [--seconds 180] [--build build-fuzz] [--only NAME]
#
# Needs clang-14 and libFuzzer (Debian 12: apt-get install clang-14 libclang-rt-14-dev).
set -u
cd "$(dirname "$0")/.."
seconds=180
build_dir=build-fuzz
only=""
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --build) build_dir="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    -h|--help) sed -n 2,10p "$0"; exit 0 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done

for tool in clang-14 clang++-14 cmake ninja; do
  command -v "$tool" >/dev/null || { echo "fuzz.sh: $tool is missing (apt-get install clang-14 cmake ninja-build)" >&2; exit 2; }
done
fuzzer_lib=$(clang-14 -print-file-name=libclang_rt.fuzzer-x86_64.a)
if [ ! -f "$fuzzer_lib" ]; then
  fuzzer_lib=$(ls /usr/lib/llvm-14/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a 2>/dev/null | head -1)
fi
[ -n "$fuzzer_lib" ] && [ -f "$fuzzer_lib" ] || {
  echo "fuzz.sh: libFuzzer is missing (apt-get install libclang-rt-14-dev)" >&2; exit 2; }

targets="tum_lists trajectory config map_file mesh_file png_decoder"
[ -n "$only" ] && targets="$only"

mkdir -p "$build_dir"
CC=clang-14 CXX=clang++-14 cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DRGBDMAP_SANITIZE=fuzzer -DRGBDMAP_BUILD_TESTS=OFF -DRGBDMAP_BUILD_BENCH=OFF >"$build_dir/cmake.log" 2>&1 \
  || { cat "$build_dir/cmake.log"; exit 2; }
cmake --build "$build_dir" -j2 --target $(for t in $targets; do printf 'fuzz_%s ' "$t"; done) || exit 2

# Seeds: the real files of the shared data and the presets.
data=../shared/data
seeds="$build_dir/seeds"
rm -rf "$seeds"
mkdir -p "$seeds"/{tum_lists,trajectory,config,map_file,mesh_file,png_decoder} "$build_dir/crashes"
for seq in "$data"/tum/*/; do
  name=$(basename "$seq")
  { head -c 3000 "$seq/rgb.txt"; printf '\001'; head -c 3000 "$seq/depth.txt"; printf '\001';
    head -c 6000 "$seq/groundtruth.txt"; } >"$seeds/tum_lists/$name"
  head -c 8000 "$seq/groundtruth.txt" >"$seeds/trajectory/$name"
done
for preset in config/*.yaml; do
  { echo "map.voxel_size=0.02"; cat "$preset"; } >"$seeds/config/$(basename "$preset")"
done
seed_map="$build_dir/seed_map.pcd"
printf 'VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n0 0 1 4.2e6\n1 2 3 0\n' >"$seed_map"
{ printf '\000'; cat "$seed_map"; } >"$seeds/map_file/ascii.pcd"
{ printf '\001'; printf 'ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 1\n1 2 3\n'; } >"$seeds/map_file/ascii.ply"

# A binary PLY mesh as --mesh writes it: 3 vertices (float xyz, uchar rgb), one triangle.
{ printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n'
  printf 'property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n'
  printf 'element face 1\nproperty list uchar int vertex_indices\nend_header\n'
  head -c 45 /dev/zero
  printf '\003\000\000\000\000\001\000\000\000\002\000\000\000'; } >"$seeds/mesh_file/triangle.ply"

# Two small PNGs (a mode byte first: 1 colour, 3 depth, CRCs recomputed): 4x3 RGB with the
# Sub, Up and Paeth filters, 3x3 16-bit grey with Sub, Average and Paeth.
printf '\001\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x04\x00\x00\x00\x03\x08\x02\x00\x00\x00\x3b\x96\x39\x91\x00\x00\x00\x32\x49\x44\x41\x54\x78\xda\x01\x27\x00\xd8\xff\x01\x44\x20\x82\x3c\xfd\xe6\xf1\xc2\x6b\x30\xf9\x0e\x02\xc7\xdd\x01\xe4\x88\x75\x34\xa2\x0f\x0b\x0d\x04\x04\xc3\x6e\xd8\x0e\x71\xe0\xfd\x77\xb0\x76\x70\xeb\x5e\x35\x12\x46\x82\x2d\xb8\x7f\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82' \
  >"$seeds/png_decoder/rgb.png"
printf '\003\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x03\x00\x00\x00\x03\x10\x00\x00\x00\x00\x23\xd3\x36\x20\x00\x00\x00\x1e\x49\x44\x41\x54\x78\xda\x63\x9c\xc2\x7d\xd5\x38\x7e\x3a\xb3\xed\xaa\x1b\x89\xb3\x27\xb2\xfc\x3f\x29\xf8\xb5\xe6\x1c\x00\x5e\xe5\x0a\x0a\x70\x75\xda\x46\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82' \
  >"$seeds/png_decoder/depth.png"

# An allocation larger than memory throws std::bad_alloc, as in a release build (a PCD header
# may declare any number of points; the reader turns that into a message), instead of an ASan
# report.
export ASAN_OPTIONS="allocator_may_return_null=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
failed=0
for t in $targets; do
  corpus="$build_dir/corpus/$t"
  mkdir -p "$corpus"
  echo "== fuzz_$t: $seconds s"
  cp "$build_dir"/crashes/"$t"-* "$corpus"/ 2>/dev/null  # earlier findings must stay fixed
  if ! "$build_dir/fuzz/fuzz_$t" "$corpus" "$seeds/$t" -max_total_time="$seconds" -timeout=10 \
      -rss_limit_mb=2048 -max_len=16384 -print_final_stats=1 \
      -artifact_prefix="$build_dir/crashes/${t}-" >"$build_dir/fuzz_$t.log" 2>&1; then
    failed=1
    echo "fuzz_$t FAILED (input in $build_dir/crashes/):"
    grep -E "ERROR|SUMMARY|Test unit written" "$build_dir/fuzz_$t.log" | head -5
  else
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build_dir/fuzz_$t.log" | tr '\n' ' '
    echo "-> no crash, hang or sanitizer report"
  fi
done
exit $failed
