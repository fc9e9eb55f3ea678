#!/usr/bin/env bash
# Writes a long real sequence from a short TUM folder: its frames played forwards, backwards,
# forwards again ... (without repeating the turning frames) until N frames, at 30 Hz, with the
# ground truth of each frame moved to its new time. The images are symbolic links to the
# originals. This is how a 723-frame replay (the length of the whole fr1/rpy) of real Kinect
# frames is measured when only its first 100 frames are at hand: every frame is real, the camera
# revisits what it saw, and the map grows only as far as the short sequence reaches, so peak
# memory is lower than on a sequence that keeps seeing new surfaces.
#
# usage: bash bench/long_real.sh SOURCE_FOLDER OUT_FOLDER [FRAMES]   (default 723)
# OUT_FOLDER's name should keep TUM's (rgbd_dataset_freiburg1_...) so the fr1 preset applies.
# Portable bash + awk only.
set -euo pipefail
export LC_ALL=C
if [ $# -lt 2 ]; then
  echo "usage: bash bench/long_real.sh SOURCE_FOLDER OUT_FOLDER [FRAMES]" >&2
  exit 2
fi
source_dir=$(cd "$1" && pwd)
out=$2
frames=${3:-723}
case "$frames" in '' | *[!0-9]*) echo "long_real.sh: '$frames' is not a whole number" >&2; exit 2 ;; esac
for f in rgb.txt depth.txt groundtruth.txt; do
  [ -f "$source_dir/$f" ] || { echo "long_real.sh: $source_dir/$f: missing" >&2; exit 1; }
done
mkdir -p "$out/rgb" "$out/depth"
out=$(cd "$out" && pwd)

# Pairs each colour frame with the nearest depth frame and the nearest ground-truth pose, then
# writes the back-and-forth order: lists, pose file and the links (as a shell script).
awk -v frames="$frames" -v src="$source_dir" -v out="$out" '
  function nearest(t, stamps, n,   i, best, d, bd) {
    best = 1; bd = -1
    for (i = 1; i <= n; ++i) { d = stamps[i] - t; if (d < 0) d = -d; if (bd < 0 || d < bd) { bd = d; best = i } }
    return best
  }
  FILENAME ~ /rgb.txt$/ && $0 !~ /^#/ && NF >= 2 { ++nr; rt[nr] = $1; rf[nr] = $2; next }
  FILENAME ~ /depth.txt$/ && $0 !~ /^#/ && NF >= 2 { ++nd; dt[nd] = $1; df[nd] = $2; next }
  FILENAME ~ /groundtruth.txt$/ && $0 !~ /^#/ && NF >= 8 {
    ++ng; gt[ng] = $1; gp[ng] = $2 " " $3 " " $4 " " $5 " " $6 " " $7 " " $8; next }
  END {
    if (nr < 2) { print "long_real.sh: fewer than 2 colour frames" > "/dev/stderr"; exit 1 }
    print "# colour images (back and forth over " src ")" > out "/rgb.txt"
    print "# depth images" > out "/depth.txt"
    print "# ground truth: timestamp tx ty tz qx qy qz qw" > out "/groundtruth.txt"
    i = 1; step = 1
    for (k = 0; k < frames; ++k) {
      t = sprintf("%.6f", 1000 + k / 30.0)
      j = nearest(rt[i], dt, nd); g = nearest(rt[i], gt, ng)
      printf "%s rgb/%d.png\n", t, k >> out "/rgb.txt"
      printf "%s depth/%d.png\n", t, k >> out "/depth.txt"
      printf "%s %s\n", t, gp[g] >> out "/groundtruth.txt"
      printf "ln -sf \"%s/%s\" \"%s/rgb/%d.png\"\n", src, rf[i], out, k
      printf "ln -sf \"%s/%s\" \"%s/depth/%d.png\"\n", src, df[j], out, k
      if (i + step < 1 || i + step > nr) step = -step
      i += step
    }
  }' "$source_dir/rgb.txt" "$source_dir/depth.txt" "$source_dir/groundtruth.txt" | sh
echo "$out: $frames frames"
