#!/usr/bin/env bash
# Mapping rate with the live viewer on, as a ratio to --viewer none on the same replay, measured
# side by side in one invocation (runs alternate, so machine load hits both alike).
# Target: the viewer costs mapping less than 10% (ratio >= 0.90).
#
# Needs a display: without one, the script runs itself under xvfb-run (Debian xvfb), where
# VTK draws with Mesa's software rasteriser on the same CPUs as mapping (a worst case: a real
# GPU takes drawing off the CPU).
#   bash bench/viewer_overhead.sh [--build DIR] [--runs N] [--source SPEC] [--rate R|max]
set -u
export LC_ALL=C
build_dir="build"
runs=7
rate="max"
root=$(cd "$(dirname "$0")/.." && pwd)
source_spec="tum:${RGBDMAP_DATA_DIR:-$root/../shared/data}/tum/rgbd_dataset_freiburg1_rpy_head100"
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build_dir="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --source) source_spec="$2"; shift 2 ;;
    --rate) rate="$2"; shift 2 ;;
    -h|--help) sed -n 2,9p "$0"; exit 0 ;;
    *) echo "viewer_overhead.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac
rgbdmap="$build_dir/rgbdmap"
if [ ! -x "$rgbdmap" ]; then
  echo "viewer_overhead.sh: $rgbdmap not found; build first" >&2
  exit 1
fi
if [ -z "${DISPLAY:-}" ]; then
  command -v xvfb-run >/dev/null || { echo "viewer_overhead.sh: no display and no xvfb-run" >&2; exit 1; }
  exec xvfb-run -a -s "-screen 0 1280x800x24" bash "$0" --build "$build_dir" --runs "$runs" \
    --source "$source_spec" --rate "$rate"
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# key from flat JSON
number() { awk -F'[:,]' -v k="\"$2\"" '$1 ~ k { gsub(/ /, "", $2); print $2; exit }' "$1"; }

run() {  # run <viewer> <n>: prints frames per second of the mapping run
  local json="$work/$1-$2.json"
  if ! "$rgbdmap" --source "$source_spec" --out "$work/$1-$2.pcd" --rate "$rate" --no-render -q \
      --viewer "$1" --stats "$json" >"$work/$1-$2.log" 2>&1; then
    echo "viewer_overhead.sh: the run with --viewer $1 failed:" >&2
    tail -5 "$work/$1-$2.log" >&2
    exit 1
  fi
  if [ "$1" = auto ] && ! grep -q "viewer: window open" "$work/$1-$2.log"; then
    echo "viewer_overhead.sh: --viewer auto opened no window:" >&2
    grep viewer "$work/$1-$2.log" >&2
    exit 1
  fi
  number "$json" frames_per_second
}

ratios=""
printf '| run | --viewer none (frames/s) | --viewer auto (frames/s) | ratio |\n| --- | --- | --- | --- |\n'
for i in $(seq 1 "$runs"); do
  # Alternate which goes first, so that warming caches favours neither.
  if [ $((i % 2)) -eq 1 ]; then
    none=$(run none "$i")
    auto=$(run auto "$i")
  else
    auto=$(run auto "$i")
    none=$(run none "$i")
  fi
  ratios="$ratios $(awk -v n="$none" -v a="$auto" 'BEGIN { print a / n }')"
  awk -v i="$i" -v n="$none" -v a="$auto" 'BEGIN { printf "| %d | %.2f | %.2f | %.3f |\n", i, n, a, a / n }'
done
# The median ratio: one run slowed by a neighbour's build moves the mean, not the median.
echo "$ratios" | tr ' ' '\n' | grep . | sort -g | awk '{ r[NR] = $1 } END {
  m = NR % 2 ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2
  printf "\nviewer on / off mapping rate, median of %d runs: %.3f (target >= 0.90): %s\n", NR, m,
    (m >= 0.90 ? "met" : "NOT met")
}'
