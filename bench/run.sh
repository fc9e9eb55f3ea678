#!/usr/bin/env bash
# Compares rgbdmap with the original PCL method (bench/original_method) side by side, in one
# invocation, on the same frames, and prints one table:
#   tum    TUM fr1/rpy (100 real frames): original every 10th vs rgbdmap every 10th / every frame
#   synth  a synthetic room with exact geometry (`rgbdmap synth`): the same three, plus F-score
#          at 1 cm and mean distance from `rgbdmap evaluate map`
#   tum-long  the same real frames played back and forth to 723 frames (the length of the whole
#          fr1/rpy; bench/long_real.sh): speed and memory on a long real replay
#   long   a longer synthetic replay (~700 frames), mainly for peak memory
# and a tracking table (ground truth used only to score): fr1/xyz, fr1/rpy, the synthetic room
# and a synthetic walk twice round an 8 x 6 m room with drifting brightness,
# tracked by rgbdmap end to end (pose.source=odometry, every frame in MAP_trajectory.txt) with
# loop closure and without it (loop.enabled=false), and, when bench/track_sequence is built, by
# OpenCV's RgbdOdometry and RgbdICPOdometry frame to frame: ATE, RPE, loops closed, ms per
# frame, frames lost, and frames dropped replaying at the recorded rate.
# Machines are shared and noisy, so each system is also given as a ratio to the original method
# measured in the same invocation; absolute times mean little on their own.
#
# Builds nothing: expects a Release build, e.g.
#   cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && cmake --build build
# Portable bash + awk only (CI machines may not have Python).
set -u
export LC_ALL=C
unset DISPLAY  # mapping alone: no viewer window (bench/viewer_overhead.sh measures that)

usage() {
  cat <<'EOF'
usage: bash bench/run.sh [options]
  --frames N        use only the first N frames of every sequence (default: all)
  --build DIR       build directory with rgbdmap and bench/original_method (default: build)
  --out FILE        also write the table (with the run's context) to FILE, e.g. bench/results.md
  --work DIR        where sequences, maps and JSON go (default: a new folder under $TMPDIR)
  --synth-frames N  frames of the synthetic sequence (default: 300; a 6 x 5 x 3 m room)
  --long-frames N   frames of the long synthetic replay (default: 700; 0 skips it)
  --long-real-frames N  frames of the real frames played back and forth (default: 723; 0 skips)
  --every N         keyframe interval of the original method and of "rgbdmap every Nth" (default 10)
  --micro           also run the Google Benchmark microbenchmarks and append their output
  --keep            keep the work folder (default: kept only when --work is given)
  --no-tracking     skip the tracking table
  --tracking-only   only the tracking table (no mapping comparison, no Open3D)
  --walk-frames N   frames of the synthetic walk with drift (default: 900, two laps; 0 skips it)
  --sequence DIR    also track this TUM folder (repeatable), e.g. the whole fr1/rpy
EOF
}

frames_limit=""
build_dir="build"
out_file=""
work_dir=""
synth_frames=300
# A room whose far walls are beyond filter.max_depth (4 m), where the depth noise is 2-3 voxels.
synth_room="--room 6x5x3"
long_frames=700
long_real_frames=723
every_n=10
run_micro=0
keep=0
run_tracking=1
run_mapping=1
walk_frames=900
extra_sequences=()
invocation="$*"  # for the results file
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames_limit="$2"; shift 2 ;;
    --build) build_dir="$2"; shift 2 ;;
    --out) out_file="$2"; shift 2 ;;
    --work) work_dir="$2"; keep=1; shift 2 ;;
    --synth-frames) synth_frames="$2"; shift 2 ;;
    --long-frames) long_frames="$2"; shift 2 ;;
    --long-real-frames) long_real_frames="$2"; shift 2 ;;
    --every) every_n="$2"; shift 2 ;;
    --micro) run_micro=1; shift ;;
    --keep) keep=1; shift ;;
    --no-tracking) run_tracking=0; shift ;;
    --tracking-only) run_mapping=0; shift ;;
    --walk-frames) walk_frames="$2"; shift 2 ;;
    --sequence) extra_sequences+=("$2"); shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run.sh: unknown option $1" >&2; usage >&2; exit 2 ;;
  esac
done
for n in "$synth_frames" "$long_frames" "$long_real_frames" "$walk_frames" "$every_n" ${frames_limit:+"$frames_limit"}; do
  case "$n" in ''|*[!0-9]*) echo "run.sh: '$n' is not a whole number" >&2; exit 2 ;; esac
done

root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root" || exit 1
case "$build_dir" in /*) ;; *) build_dir="$root/$build_dir" ;; esac
case "$out_file" in ''|/*) ;; *) out_file="$root/$out_file" ;; esac
rgbdmap="$build_dir/rgbdmap"
original="$build_dir/bench/original_method"
micro="$build_dir/bench/micro_benchmarks"
track_sequence="$build_dir/bench/track_sequence"
required=("$rgbdmap")
[ "$run_mapping" = 1 ] && required+=("$original")
for exe in "${required[@]}"; do
  if [ ! -x "$exe" ]; then
    echo "run.sh: $exe not found; build first:" >&2
    echo "  cmake -S . -B ${build_dir#"$root"/} -DCMAKE_BUILD_TYPE=Release && cmake --build ${build_dir#"$root"/}" >&2
    exit 1
  fi
done
data_dir="${RGBDMAP_DATA_DIR:-$root/../shared/data}"
tum_source="$data_dir/tum/rgbd_dataset_freiburg1_rpy_head100"
if [ ! -f "$tum_source/rgb.txt" ]; then
  echo "run.sh: $tum_source: no TUM sequence there (set RGBDMAP_DATA_DIR)" >&2
  exit 1
fi

if [ -z "$work_dir" ]; then
  work_dir=$(mktemp -d "${TMPDIR:-/tmp}/rgbdmap-bench.XXXXXX") || exit 1
fi
mkdir -p "$work_dir" || exit 1
work_dir=$(cd "$work_dir" && pwd)
rows="$work_dir/rows.tsv"
notes="$work_dir/notes.txt"
: >"$rows"
: >"$notes"
failures=0

note() { echo "$*" >>"$notes"; echo "run.sh: $*" >&2; }
load() { echo "machine load $1: $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?') (1, 5, 15 min averages, $(getconf _NPROCESSORS_ONLN 2>/dev/null || echo '?') cores)" >>"$notes"; }
load "at start"

# Seconds since the epoch with sub-second resolution (bash 5's EPOCHREALTIME, else GNU date).
now() {
  if [ -n "${EPOCHREALTIME:-}" ]; then echo "$EPOCHREALTIME"; else date +%s.%N; fi
}
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3f", b - a }'; }

# json_number FILE KEY [OBJECT]: the number after "KEY": (inside "OBJECT" when given), or
# nothing. Works on any formatting of the file (it is read as one string).
json_number() {
  [ -f "$1" ] || return 0
  awk -v key="$2" -v obj="${3:-}" 'BEGIN { RS = "\001" }
    {
      s = $0
      if (obj != "") { i = index(s, "\"" obj "\""); if (!i) exit; s = substr(s, i + length(obj) + 2) }
      while ((i = index(s, "\"" key "\"")) > 0) {
        s = substr(s, i + length(key) + 2)
        if (match(s, /^[ \t\r\n]*:[ \t\r\n]*-?[0-9][0-9.eE+-]*/)) {
          v = substr(s, RSTART, RLENGTH); sub(/^[^:]*:[ \t\r\n]*/, "", v); print v; exit
        }
      }
    }' "$1"
}

# A copy of a TUM folder's lists cut to the first N colour frames (and the depth images up to
# just after them); images and ground truth are linked, not copied. The folder keeps its name,
# so both programs pick the same camera preset from it.
cut_tum() {  # SOURCE DEST N
  local src="$1" dst="$2" n="$3"
  mkdir -p "$dst" || return 1
  local item
  for item in rgb depth groundtruth.txt accelerometer.txt; do
    [ -e "$src/$item" ] && ln -sfn "$src/$item" "$dst/$item"
  done
  for item in "$src"/*; do  # anything else the sequence carries (e.g. a camera file)
    case "${item##*/}" in rgb|depth|rgb.txt|depth.txt|groundtruth.txt|accelerometer.txt) ;;
      *) ln -sfn "$item" "$dst/${item##*/}" ;; esac
  done
  awk -v n="$n" '/^#/ { print; next } { if (++count > n) exit; print }' "$src/rgb.txt" >"$dst/rgb.txt"
  local last
  last=$(awk '!/^#/ && NF { t = $1 } END { print t }' "$dst/rgb.txt")
  awk -v last="$last" '/^#/ { print; next } NF && $1 + 0 <= last + 0.02 { print }' \
    "$src/depth.txt" >"$dst/depth.txt"
}

# add_row SCENARIO SYSTEM FRAMES FUSED WALL FPS KF_P50 KF_P95 RSS POINTS FSCORE MEAN_MM BASELINE
add_row() {
  local IFS=$'\t'
  echo "$*" >>"$rows"
}
dash() { if [ -n "$1" ]; then echo "$1"; else echo "-"; fi; }

# F-score at 1 cm and mean distance (mm) of MAP against the synthetic scene SCENE, or "- -".
evaluate_map() {  # MAP SCENE JSON
  local map="$1" scene="$2" json="$3"
  if [ "$have_evaluate" != 1 ] || [ ! -f "$map" ]; then echo "- -"; return; fi
  if ! "$rgbdmap" evaluate map "$map" --scene "$scene" --json "$json" >"$json.log" 2>&1; then
    note "evaluate failed on $map (see $json.log)"
    echo "- -"
    return
  fi
  local f="" mean="" key
  for key in f_score fscore f1 f_score_1cm; do
    f=$(json_number "$json" "$key"); [ -n "$f" ] && break
  done
  for key in mean_distance_mm mean_error_mm mean_mm; do
    mean=$(json_number "$json" "$key"); [ -n "$mean" ] && break
  done
  if [ -z "$mean" ]; then
    for key in mean_distance_m mean_distance mean_error_m mean_error; do
      mean=$(json_number "$json" "$key")
      if [ -n "$mean" ]; then mean=$(awk -v m="$mean" 'BEGIN { printf "%.2f", m * 1000 }'); break; fi
    done
  fi
  [ -z "$f" ] && note "evaluate: no F-score in $json"
  echo "$(dash "$f") $(dash "$mean")"
}

run_original() {  # SCENARIO SEQUENCE EXACT_SCENE(or empty)
  local scenario="$1" seq="$2" scene="$3" base="$work_dir/$1-original"
  echo "== $scenario: original method, every ${every_n}th frame" >&2
  local t0 t1
  t0=$(now)
  if ! "$original" "$seq" --every "$every_n" --out "$base.pcd" --json "$base.json" -q \
      >"$base.log" 2>&1; then
    note "$scenario: original_method failed (see $base.log)"
    failures=$((failures + 1))
    add_row "$scenario" "original every $every_n" - - - - - - - - - - 1
    return
  fi
  t1=$(now)
  local overflows
  overflows=$(json_number "$base.json" voxel_grid_overflows)
  if [ "${overflows:-0}" != 0 ]; then
    note "$scenario: pcl::VoxelGrid returned its input unfiltered $overflows time(s) (extent/leaf overflows 32-bit indices; the original's bug, kept)"
  fi
  local quality
  quality=$(if [ -n "$scene" ]; then evaluate_map "$base.pcd" "$scene" "$base-eval.json"; else echo "- -"; fi)
  add_row "$scenario" "original every $every_n" \
    "$(json_number "$base.json" frames)" "$(json_number "$base.json" keyframes)" \
    "$(elapsed "$t0" "$t1")" "$(json_number "$base.json" frames_per_second)" \
    "$(json_number "$base.json" p50_ms keyframe_ms)" "$(json_number "$base.json" p95_ms keyframe_ms)" \
    "$(json_number "$base.json" peak_rss_mb)" "$(json_number "$base.json" map_points)" \
    ${quality} 1
}

run_rgbdmap() {  # SCENARIO SEQUENCE EVERY_N EXACT_SCENE(or empty)
  local scenario="$1" seq="$2" n="$3" scene="$4" base="$work_dir/$1-rgbdmap-every$3"
  local label="rgbdmap every $n"
  [ "$n" = 1 ] && label="rgbdmap every frame"
  echo "== $scenario: $label" >&2
  local t0 t1
  t0=$(now)
  if ! "$rgbdmap" --source "tum:$seq" --out "$base.pcd" --rate max -q --no-render \
      --stats "$base.json" --set "keyframe.every_n=$n" >"$base.log" 2>&1; then
    note "$scenario: rgbdmap ($label) failed (see $base.log)"
    failures=$((failures + 1))
    add_row "$scenario" "$label" - - - - - - - - - - 0
    return
  fi
  t1=$(now)
  local quality
  quality=$(if [ -n "$scene" ]; then evaluate_map "$base.pcd" "$scene" "$base-eval.json"; else echo "- -"; fi)
  add_row "$scenario" "$label" \
    "$(json_number "$base.json" frames_processed)" "$(json_number "$base.json" keyframes)" \
    "$(elapsed "$t0" "$t1")" "$(json_number "$base.json" frames_per_second)" \
    "$(json_number "$base.json" p50_ms integrate)" "$(dash "$(json_number "$base.json" p95_ms integrate)")" \
    "$(json_number "$base.json" peak_rss_mb)" "$(json_number "$base.json" map_points)" \
    ${quality} 0
}

# Open3D's ScalableTSDFVolume (bench/open3d_tsdf.py, Debian's python3-open3d) as a peer: the
# same frames, the poses and intrinsics rgbdmap used (its keyframe file and map.yaml from the
# every-frame run), voxel 1 cm, truncation 4 cm, the same maximum depth. Skipped when absent.
python=/usr/bin/python3
[ -x "$python" ] || python=python3
have_open3d=0
"$python" -c 'import open3d' >/dev/null 2>&1 && have_open3d=1
[ "$have_open3d" = 1 ] || note "Open3D: skipped (no python3-open3d; bash scripts/setup.sh --bench)"
run_open3d() {  # SCENARIO SEQUENCE EVERY_N EXACT_SCENE(or empty) THREADS(empty: its default)
  [ "$have_open3d" = 1 ] || return 0
  local scenario="$1" seq="$2" n="$3" scene="$4" threads="$5"
  local base="$work_dir/$1-open3d-every$3${threads:+-threads$threads}"
  local poses="$work_dir/$1-rgbdmap-every1_keyframes.txt" yaml="$work_dir/$1-rgbdmap-every1.yaml"
  local label="open3d every $n"
  [ "$n" = 1 ] && label="open3d every frame"
  [ -n "$threads" ] && label="$label, $threads thread"
  echo "== $scenario: $label" >&2
  if [ ! -f "$poses" ] || [ ! -f "$yaml" ]; then
    note "$scenario: $label skipped: no poses from rgbdmap's every-frame run"
    return 0
  fi
  yaml_value() { awk -v key="$1:" '$1 == key { print $2; exit }' "$yaml"; }
  local t0 t1
  t0=$(now)
  # Its default threads (every core, as rgbdmap's replay uses) is the fair comparison; one
  # OpenMP thread shows what it does per core.
  if ! env ${threads:+OMP_NUM_THREADS=$threads} "$python" "$root/bench/open3d_tsdf.py" "$seq" "$poses" "$base.pcd" \
      --every "$n" --fx "$(yaml_value fx)" --fy "$(yaml_value fy)" --cx "$(yaml_value cx)" \
      --cy "$(yaml_value cy)" --depth-scale "$(yaml_value depth_scale)" \
      --max-depth "$(yaml_value max_depth)" >"$base.json" 2>"$base.log"; then
    note "$scenario: $label failed (see $base.log)"
    failures=$((failures + 1))
    return 0
  fi
  t1=$(now)
  local quality
  quality=$(if [ -n "$scene" ]; then evaluate_map "$base.pcd" "$scene" "$base-eval.json"; else echo "- -"; fi)
  add_row "$scenario" "$label" \
    "$(json_number "$base.json" frames)" "$(json_number "$base.json" keyframes)" \
    "$(elapsed "$t0" "$t1")" "$(json_number "$base.json" frames_per_second)" - - \
    "$(json_number "$base.json" peak_rss_mb)" "$(json_number "$base.json" map_points)" \
    ${quality} 0
}

run_scenario() {  # SCENARIO SEQUENCE EXACT_SCENE(or empty)
  [ "$run_mapping" = 1 ] || return 0
  run_original "$1" "$2" "$3"
  run_rgbdmap "$1" "$2" "$every_n" "$3"
  run_rgbdmap "$1" "$2" 1 "$3"
  run_open3d "$1" "$2" 1 "$3" ""
  run_open3d "$1" "$2" 1 "$3" 1
  run_open3d "$1" "$2" "$every_n" "$3" ""
}

# --- (a) TUM fr1/rpy, real frames -----------------------------------------------------------
tum_seq="$tum_source"
if [ -n "$frames_limit" ]; then
  tum_seq="$work_dir/tum/${tum_source##*/}"
  cut_tum "$tum_source" "$tum_seq" "$frames_limit" || { echo "run.sh: cannot cut $tum_source" >&2; exit 1; }
fi
run_scenario tum "$tum_seq" ""

# --- (a2) the same real frames back and forth, as long as the whole fr1/rpy (bench/long_real.sh)
if [ "$long_real_frames" -gt 0 ] && [ "$run_mapping" = 1 ]; then
  n="$long_real_frames"
  [ -n "$frames_limit" ] && [ "$frames_limit" -lt "$n" ] && n="$frames_limit"
  long_real="$work_dir/rgbd_dataset_freiburg1_rpy_long"  # the name keeps the fr1 preset
  if bash "$root/bench/long_real.sh" "$tum_source" "$long_real" "$n" >/dev/null; then
    run_scenario tum-long "$long_real" ""
  else
    note "tum-long: bench/long_real.sh failed"
  fi
fi

# --- (b), (c) synthetic sequences with exact geometry -----------------------------------------
have_synth=0
have_evaluate=0
# has_subcommand NAME [PARENT]: whether `rgbdmap [PARENT] --help` lists NAME as a subcommand
# (an unknown subcommand is not an error to CLI11: it would print the main help and succeed).
has_subcommand() {
  "$rgbdmap" ${2:+"$2"} --help 2>/dev/null |
    awk -v name="$1" '/^Subcommands:/ { listed = 1; next } listed && $1 == name { found = 1 } END { exit !found }'
}
has_subcommand synth && have_synth=1
has_subcommand evaluate && "$rgbdmap" evaluate --help 2>/dev/null | grep -q "map" && have_evaluate=1
[ "$have_synth" = 1 ] || note "synth, long: skipped: this rgbdmap has no 'synth' subcommand"
[ "$have_synth" = 1 ] && [ "$have_evaluate" = 0 ] &&
  note "synth: no F-score: this rgbdmap has no 'evaluate map' subcommand"

make_synth() {  # DEST FRAMES
  echo "== generating a synthetic sequence of $2 frames" >&2
  local t0 t1
  t0=$(now)
  if ! "$rgbdmap" synth --out "$1" --frames "$2" $synth_room >"$1.log" 2>&1; then
    note "rgbdmap synth --out $1 --frames $2 failed (see $1.log)"
    return 1
  fi
  t1=$(now)
  echo "synthetic sequence of $2 frames generated in $(elapsed "$t0" "$t1") s: $1" >>"$notes"
}

# The mesh (--mesh) of a sequence fused every frame: marching cubes on the fusion thread and the
# PLY write on the writer thread, per save (the final one: max), as a note under the table.
mesh_note() {  # SCENARIO SEQUENCE
  [ "$run_mapping" = 1 ] || return 0
  "$rgbdmap" --help 2>/dev/null | grep -q -- "--mesh" || { note "mesh: this rgbdmap has no --mesh"; return 0; }
  local base="$work_dir/$1-rgbdmap-mesh"
  echo "== $1: rgbdmap every frame --mesh" >&2
  if ! "$rgbdmap" --source "tum:$2" --out "$base.pcd" --mesh "$base.ply" --rate max -q --no-render \
      --stats "$base.json" --set keyframe.every_n=1 >"$base.log" 2>&1; then
    note "$1: rgbdmap --mesh failed (see $base.log)"
    failures=$((failures + 1))
    return 0
  fi
  note "$1: mesh of $(json_number "$base.json" map_points) map points: $(json_number "$base.json" mesh_triangles) triangles, extraction $(json_number "$base.json" max_ms mesh_extract) ms, PLY write $(json_number "$base.json" max_ms mesh_write) ms (largest save)"
}

if [ "$have_synth" = 1 ]; then
  n="$synth_frames"
  [ -n "$frames_limit" ] && [ "$frames_limit" -lt "$n" ] && n="$frames_limit"
  if make_synth "$work_dir/synth" "$n"; then
    run_scenario synth "$work_dir/synth" "$work_dir/synth"
    mesh_note synth "$work_dir/synth"
  fi
  if [ "$long_frames" -gt 0 ] && [ "$run_mapping" = 1 ]; then
    n="$long_frames"
    [ -n "$frames_limit" ] && [ "$frames_limit" -lt "$n" ] && n="$frames_limit"
    if make_synth "$work_dir/long" "$n"; then run_scenario long "$work_dir/long" "$work_dir/long"; fi
  fi
fi

# --- (d) tracking: every frame, ground truth used only to score ------------------------------
track_rows="$work_dir/track_rows.tsv"
: >"$track_rows"
cm() { awk -v m="$1" 'BEGIN { if (m == "") print "-"; else printf "%.2f", m * 100 }'; }

# add_track_row SEQUENCE SYSTEM FRAMES ATE_CM RPE_CM RPE_DEG LOST LOOPS MS_P50 MS_P95 DROPPED
add_track_row() {
  local IFS=$'\t'
  echo "$*" >>"$track_rows"
}

track_scenario() {  # ID NAME FOLDER
  local name="$2" seq="$3" mode
  for mode in loops odometry; do
    local base="$work_dir/track-$1-$mode" label="rgbdmap, loop closure" loop_set=true
    if [ "$mode" = odometry ]; then label="rgbdmap, odometry only"; loop_set=false; fi
    echo "== tracking $name: $label, every frame (--rate max), then at the recorded rate" >&2
    local ate="" rpe="" rpe_deg="" dropped="-"
    if "$rgbdmap" --source "tum:$seq" --out "$base.pcd" --rate max -q --no-render \
        --stats "$base.json" --set pose.source=odometry --set loop.enabled=$loop_set \
        >"$base.log" 2>&1; then
      if "$rgbdmap" evaluate trajectory --estimate "${base}_trajectory.txt" \
          --groundtruth "$seq/groundtruth.txt" --json "$base-ate.json" >"$base-ate.log" 2>&1; then
        ate=$(json_number "$base-ate.json" ate_rmse_m)
        rpe=$(json_number "$base-ate.json" rpe_trans_rmse_m)
        rpe_deg=$(json_number "$base-ate.json" rpe_rot_rmse_deg)
      else
        note "tracking $name: evaluate trajectory failed (see $base-ate.log)"
      fi
    else
      note "tracking $name ($label): rgbdmap failed (see $base.log)"
      failures=$((failures + 1))
    fi
    # As a live camera: the replay keeps the recorded pace and drops what the mapper cannot take.
    if "$rgbdmap" --source "tum:$seq" --out "$base-rate1.pcd" --rate 1 -q --no-render \
        --stats "$base-rate1.json" --set pose.source=odometry --set loop.enabled=$loop_set \
        >"$base-rate1.log" 2>&1; then
      dropped="$(json_number "$base-rate1.json" frames_dropped)/$(json_number "$base-rate1.json" frames_captured)"
    else
      note "tracking $name: rgbdmap --rate 1 ($label) failed (see $base-rate1.log)"
    fi
    local loops="-"
    [ "$mode" = loops ] &&
      loops="$(json_number "$base.json" loops_accepted)/$(json_number "$base.json" loop_candidates)"
    add_track_row "$name" "$label" "$(json_number "$base.json" frames_processed)" \
      "$(cm "$ate")" "$(cm "$rpe")" "$(dash "$rpe_deg")" "$(json_number "$base.json" frames_lost)" \
      "$loops" "$(json_number "$base-rate1.json" p50_ms pose)" \
      "$(json_number "$base-rate1.json" p95_ms pose)" \
      "$dropped"
  done
  local base="$work_dir/track-$1"

  if [ ! -x "$track_sequence" ]; then return; fi
  echo "== tracking $name: OpenCV frame to frame (bench/track_sequence)" >&2
  if ! "$track_sequence" --sequence "$seq" --methods opencv_rgbd,opencv_rgbd_icp \
      --json "$base-opencv.json" >"$base-opencv.log" 2>&1; then
    note "tracking $name: track_sequence failed (see $base-opencv.log)"
    return
  fi
  local method label frames
  frames=$(json_number "$base-opencv.json" frames)
  for method in opencv_rgbd opencv_rgbd_icp; do
    label="OpenCV RgbdOdometry f2f"
    [ "$method" = opencv_rgbd_icp ] && label="OpenCV RgbdICPOdometry f2f"
    add_track_row "$name" "$label" "$frames" \
      "$(cm "$(json_number "$base-opencv.json" ate_rmse "$method")")" \
      "$(cm "$(json_number "$base-opencv.json" rpe_translation_rmse "$method")")" \
      "$(dash "$(json_number "$base-opencv.json" rpe_rotation_rmse "$method")")" \
      "$(json_number "$base-opencv.json" lost "$method")" "-" \
      "$(json_number "$base-opencv.json" median_ms "$method")" \
      "$(json_number "$base-opencv.json" p95_ms "$method")" "-"
  done
}

if [ "$run_tracking" = 1 ]; then
  xyz_seq="$data_dir/tum/rgbd_dataset_freiburg1_xyz"
  if [ -n "$frames_limit" ]; then
    cut_tum "$xyz_seq" "$work_dir/tum/${xyz_seq##*/}" "$frames_limit" && xyz_seq="$work_dir/tum/${xyz_seq##*/}"
  fi
  [ -f "$xyz_seq/rgb.txt" ] && track_scenario xyz fr1/xyz "$xyz_seq"
  track_scenario rpy fr1/rpy "$tum_seq"
  [ -f "$work_dir/synth/rgb.txt" ] && track_scenario synth synth "$work_dir/synth"
  # Twice round a larger room (35 m walked in 30 s) with the colour gain drifting by 15%:
  # odometry drifts about 1.3 cm (ATE), and the second lap revisits the first.
  if [ "$walk_frames" -gt 0 ] && [ "$have_synth" = 1 ]; then
    if "$rgbdmap" synth --help 2>/dev/null | grep -q -- "--path"; then
      n="$walk_frames"
      [ -n "$frames_limit" ] && [ "$frames_limit" -lt "$n" ] && n="$frames_limit"
      echo "== generating a synthetic walk of $n frames" >&2
      if "$rgbdmap" synth --out "$work_dir/walk" --frames "$n" --room 8x6x3 --path walk \
          --loop-seconds 15 --brightness-drift 0.15 >"$work_dir/walk.log" 2>&1; then
        track_scenario walk "synthetic walk 8x6 m" "$work_dir/walk"
      else
        note "tracking: rgbdmap synth --path walk failed (see $work_dir/walk.log)"
      fi
    else
      note "tracking: no synthetic walk: this rgbdmap synth has no --path"
    fi
  fi
  for extra in ${extra_sequences[@]+"${extra_sequences[@]}"}; do
    if [ -f "$extra/rgb.txt" ] && [ -f "$extra/groundtruth.txt" ]; then
      track_scenario "extra-${extra##*/}" "${extra##*/}" "$extra"
    else
      note "tracking: $extra: not a TUM folder with rgb.txt and groundtruth.txt; skipped"
    fi
  done
  [ -x "$track_sequence" ] ||
    note "tracking: no OpenCV rows: $track_sequence is not built"
fi

# --- the table --------------------------------------------------------------------------------
# rgbdmap's frames/s over Open3D's, every frame fused, per scenario of this invocation.
awk -F '\t' '$2 == "rgbdmap every frame" { r[$1] = $6 } $2 == "open3d every frame" { o[$1] = $6 }
  END { for (s in r) if ((s in o) && o[s] > 0) printf "%s: rgbdmap every frame at %.2fx the frames/s of Open3D every frame\n", s, r[s] / o[s] }' \
  "$rows" >>"$notes"
load "at end"
table="$work_dir/table.txt"
awk -F '\t' '
  function num(x) { return x ~ /^-?[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$/ }
  function fmt(x, digits) { return num(x) ? sprintf("%." digits "f", x) : "-" }
  function ratio(x, base, inverse) {
    if (!num(x) || !num(base) || x + 0 == 0 || base + 0 == 0) return "-"
    return sprintf("%.2f", inverse ? base / x : x / base)
  }
  { for (i = 1; i <= NF; ++i) field[NR, i] = $i; if ($13 == 1) base_row[$1] = NR; n = NR }
  END {
    header = "scenario|system|frames|fused|wall s|frames/s|kf ms p50|kf ms p95|peak RSS MB|map points|F@1cm|mean mm|fps x|kf speed-up|RSS x|MB/100 fr"
    cols = split(header, h, "|")
    for (c = 1; c <= cols; ++c) { cell[0, c] = h[c]; width[c] = length(h[c]) }
    for (r = 1; r <= n; ++r) {
      b = base_row[field[r, 1]]
      cell[r, 1] = field[r, 1]; cell[r, 2] = field[r, 2]
      cell[r, 3] = fmt(field[r, 3], 0); cell[r, 4] = fmt(field[r, 4], 0)
      cell[r, 5] = fmt(field[r, 5], 2); cell[r, 6] = fmt(field[r, 6], 2)
      cell[r, 7] = fmt(field[r, 7], 1); cell[r, 8] = fmt(field[r, 8], 1)
      cell[r, 9] = fmt(field[r, 9], 0); cell[r, 10] = fmt(field[r, 10], 0)
      cell[r, 11] = fmt(field[r, 11], 3); cell[r, 12] = fmt(field[r, 12], 2)
      cell[r, 13] = b ? ratio(field[r, 6], field[b, 6], 0) : "-"
      cell[r, 14] = b ? ratio(field[r, 7], field[b, 7], 1) : "-"
      cell[r, 15] = b ? ratio(field[r, 9], field[b, 9], 0) : "-"
      cell[r, 16] = ratio(field[r, 9], field[r, 3] / 100, 0)
      for (c = 1; c <= cols; ++c) if (length(cell[r, c]) > width[c]) width[c] = length(cell[r, c])
    }
    for (r = 0; r <= n; ++r) {
      line = ""
      for (c = 1; c <= cols; ++c) {
        f = (c <= 2) ? "%-" width[c] "s" : "%" width[c] "s"
        line = line (c > 1 ? "  " : "") sprintf(f, cell[r, c])
      }
      print line
      if (r == 0) { rule = line; gsub(/./, "-", rule); print rule }
    }
  }' "$rows" >"$table"

legend="frames: frames read; fused: keyframes integrated; wall s: whole process, measured by this
script; frames/s and kf ms (per-keyframe integration time) as each program reports them;
peak RSS: VmHWM. F@1cm / mean mm: map against the exact synthetic geometry (rgbdmap evaluate).
Ratios are against the original method in the same scenario of this invocation: fps x = frames/s
ratio, kf speed-up = original kf ms p50 / this kf ms p50, RSS x = peak RSS ratio; MB/100 fr = peak
RSS per 100 frames read. Open3D runs with its default threads (every core, like rgbdmap's
replay) and, in its own row, with one.
The machine load (uptime) before and after the run is in the notes: compare ratios, not times."

track_table="$work_dir/track_table.txt"
: >"$track_table"
if [ -s "$track_rows" ]; then
  awk -F '\t' '
    { for (i = 1; i <= NF; ++i) cell[NR, i] = $i; n = NR }
    END {
      header = "sequence|tracker|frames|ATE cm|RPE cm/s|RPE deg/s|lost|loops|ms p50|ms p95|dropped at --rate 1"
      cols = split(header, h, "|")
      for (c = 1; c <= cols; ++c) { cell[0, c] = h[c]; width[c] = length(h[c]) }
      for (r = 1; r <= n; ++r) {
        for (c = 9; c <= 10; ++c) if (cell[r, c] ~ /^[0-9.]+$/) cell[r, c] = sprintf("%.1f", cell[r, c])
        if (cell[r, 6] ~ /^[0-9.]+$/) cell[r, 6] = sprintf("%.2f", cell[r, 6])
        for (c = 1; c <= cols; ++c) {
          if (cell[r, c] == "") cell[r, c] = "-"
          if (length(cell[r, c]) > width[c]) width[c] = length(cell[r, c])
        }
      }
      for (r = 0; r <= n; ++r) {
        line = ""
        for (c = 1; c <= cols; ++c) {
          f = (c <= 2) ? "%-" width[c] "s" : "%" width[c] "s"
          line = line (c > 1 ? "  " : "") sprintf(f, cell[r, c])
        }
        print line
        if (r == 0) { rule = line; gsub(/./, "-", rule); print rule }
      }
    }' "$track_rows" >"$track_table"
fi
track_legend="Tracking: every frame of each sequence, ground truth used only to score. rgbdmap runs end to
end (pose.source=odometry, fusion on, --rate max), with loop closure (the default) and without
(loop.enabled=false); ATE (after rigid alignment) and RPE over 1 s of MAP_trajectory.txt, which
has every frame (a lost frame at its predicted pose) with the pose graph's final corrections;
loops: loops accepted / candidates tried geometrically (PnP, dense check); ms: tracking alone
per frame at the recorded rate (--rate 1, the stats' pose latency, decoding excluded; OpenCV
rows: every frame in a row); lost: frames tracking gave up on;
dropped: frames dropped (of those read) replaying at the recorded rate (--rate 1), as a live
camera. OpenCV rows: bench/track_sequence, frame to frame, same frames, same invocation."

if [ -s "$rows" ]; then cat "$table"; echo; echo "$legend"; fi
if [ -s "$track_table" ]; then echo; cat "$track_table"; echo; echo "$track_legend"; fi
if [ -s "$notes" ]; then echo; cat "$notes"; fi

micro_out=""
if [ "$run_micro" = 1 ]; then
  if [ -x "$micro" ]; then
    echo "== microbenchmarks" >&2
    micro_out="$work_dir/micro.txt"
    "$micro" --benchmark_min_time=0.5 >"$micro_out" 2>&1 || { note "micro_benchmarks failed"; failures=$((failures + 1)); }
    echo
    cat "$micro_out"
  else
    note "$micro not built; no microbenchmarks"
  fi
fi

if [ -n "$out_file" ]; then
  {
    if [ "$run_mapping" = 1 ]; then echo "# rgbdmap vs the original method"; else echo "# rgbdmap tracking, with and without loop closure"; fi
    echo
    echo "- date: $(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "- host: $(uname -n), $(getconf _NPROCESSORS_ONLN 2>/dev/null || echo '?') cores, $(uname -sr)"
    # The results file itself does not count as a change (when it is inside the checkout).
    local_changes=(git -C "$root" diff --quiet HEAD --)
    case "$out_file" in "$root"/*) local_changes+=(. ":(exclude)${out_file#"$root"/}") ;; esac
    echo "- commit: $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)$("${local_changes[@]}" 2>/dev/null || echo ' (with uncommitted changes)')"
    echo "- command: bash bench/run.sh $invocation"
    echo
    if [ -s "$rows" ]; then
      echo '```'; cat "$table"; echo '```'; echo; echo "$legend"
    fi
    if [ -s "$track_table" ]; then
      echo; echo "## Tracking"; echo; echo '```'; cat "$track_table"; echo '```'; echo; echo "$track_legend"
    fi
    if [ -s "$notes" ]; then echo; echo "Notes:"; echo; sed 's/^/- /' "$notes"; fi
    if [ -n "$micro_out" ]; then
      echo; echo "## Microbenchmarks"; echo
      echo "One fr1/rpy frame (640x480). Google Benchmark's \"Library was built as DEBUG\" warning is about"
      echo "Debian's libbenchmark package itself (built without NDEBUG); the code measured is Release."
      echo; echo '```'; cat "$micro_out"; echo '```'
    fi
  } >"$out_file"
  echo "table written to $out_file" >&2
fi

if [ "$keep" = 1 ]; then echo "maps, logs and JSON kept in $work_dir" >&2; else rm -rf "$work_dir"; fi
[ "$failures" = 0 ]
