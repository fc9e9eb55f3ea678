#!/usr/bin/env bash
# Tracking on many excerpts of a few real sequences: a short real sequence's ATE jumps by tenths
# of a centimetre between neighbouring settings (one keyframe placed differently), so a default
# is judged on the mean over excerpts, not on one run. Each excerpt starts at another frame and
# keeps every k-th one (k = 2, 3: a camera moving two or three times as fast); each is mapped
# losslessly (`--rate max`, odometry and loops: the result does not depend on the machine's load)
# with the default configuration and with the options after `--`, in the same invocation, and
# scored with `rgbdmap evaluate trajectory`. Prints ATE (cm) per excerpt and the means.
#   bash bench/excerpts.sh [--build DIR] [--starts "0 10 20"] [--strides "1 2 3"] SEQ... \
#       [-- rgbdmap options...]
# An excerpt folder links the sequence's images and ground truth and lists its own rgb.txt; its
# name keeps the sequence's, so that the camera preset it implies (tum_fr1, ...) is kept.
set -u
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir="build"
starts="0 10 20 30 40"
strides="1 2 3"
sequences=()
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --starts) starts="$2"; shift 2 ;;
    --strides) strides="$2"; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n 2,12p "$0"; exit 0 ;;
    -*) echo "excerpts.sh: unknown option $1" >&2; exit 2 ;;
    *) sequences+=("$1"); shift ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac
rgbdmap="$build_dir/rgbdmap"
[ -x "$rgbdmap" ] || { echo "excerpts.sh: $rgbdmap not found; build first" >&2; exit 1; }
[ ${#sequences[@]} -gt 0 ] || { echo "excerpts.sh: name at least one TUM folder" >&2; exit 2; }
work=$(mktemp -d "${TMPDIR:-/tmp}/rgbdmap-excerpts-XXXXXX")
trap 'rm -rf "$work"' EXIT

# ATE (cm) of one excerpt mapped with the given options.
ate() {
  local folder=$1 out=$2
  shift 2
  mkdir -p "$out"
  "$rgbdmap" --source "tum:$folder" --rate max --out "$out/map.pcd" --no-render --viewer none \
    --set pose.source=odometry "$@" >"$out/log.txt" 2>&1 || { echo "-"; return; }
  "$rgbdmap" evaluate trajectory --groundtruth "$folder/groundtruth.txt" \
    --estimate "$out/map_trajectory.txt" 2>/dev/null | awk '/^ATE/ {printf "%.2f", $4 * 100}'
}

printf '%-48s %10s %10s\n' "excerpt (ATE cm)" "defaults" "options"
for sequence in "${sequences[@]}"; do
  sequence=$(cd "$sequence" && pwd)
  name=$(basename "$sequence")
  for k in $strides; do
    for s in $starts; do
      folder="$work/${name}_from${s}_every${k}"
      mkdir -p "$folder"
      for f in rgb depth depth.txt groundtruth.txt accelerometer.txt; do
        [ -e "$sequence/$f" ] && ln -s "$sequence/$f" "$folder/$f"
      done
      awk -v s="$s" -v k="$k" '/^#/ || NF == 0 {next} {if (n >= s && (n - s) % k == 0) print; n++}' \
        "$sequence/rgb.txt" >"$folder/rgb.txt"
      a=$(ate "$folder" "$folder/defaults")
      b=$(ate "$folder" "$folder/options" "${extra[@]}")
      printf '%-48s %10s %10s\n' "${name}_from${s}_every${k}" "$a" "$b"
    done
  done
done | tee "$work/table.txt"
awk '$2 != "-" && $3 != "-" {n++; a += $2; b += $3}
     END {if (n) printf "%-48s %10.2f %10.2f   (%d excerpts; ratio %.3f)\n", "mean", a / n, b / n, n, b / a}' \
  "$work/table.txt"
