#!/usr/bin/env bash
# Installs dependencies, builds, and runs the test suite three times: a release build, the
# threaded tests under ThreadSanitizer, and the rest under AddressSanitizer + UBSan. The tests
# of map quality at scale (label `scale`), the long ones (6 s or more in release, labels ending
# in `-long`, tests/long_tests.cmake) and the ROS node's and merger's (label `ros-master`) run in
# the release build only: the sanitizer runs take the shorter tests, which run the same code
# (docs/testing.md).
# Usage: bash scripts/test.sh [--quick]   (--quick: release build only)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
bash scripts/setup.sh
jobs=$(nproc)
# One test more than cores: tests that play a camera or a bag at its recorded pace, or wait for a
# master, leave a core idle. Measured on 2 cores (2026-12-07, builds incremental): release 480 ->
# 433 s, ThreadSanitizer 292 -> 247 s, all passing; the tests wait for events, not for times, and
# had passed with `stress-ng --cpu 2` beside them (docs/testing.md).
test_jobs=$((jobs + 1))

build() {  # build <dir> <target> [cmake args...]
  local dir=$1 target=$2
  shift 2
  cmake -S . -B "$dir" -G Ninja "$@" >/dev/null
  cmake --build "$dir" -j "$jobs" --target "$target"
}
# Every build compiles each layer and each test program as a few unity files rather than one file
# at a time: the 143 files of the layers and the 60 of the tests parse and instantiate the same
# third-party code over again (the command-line parser alone, 12 s in each of 15 files). The
# README's main command (scripts/demo.sh) compiles every file of the program on its own, so a
# file that misses an include fails there.
# Sanitizer builds: optimised, with line tables only (all a report's stack needs; full debug
# information made these builds a third slower), and no benchmarks.
sanitized=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DRGBDMAP_BUILD_BENCH=OFF -DCMAKE_UNITY_BUILD=ON
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG")

# Each section says when it starts and how much disk is left (2026-12-02: the release tests leave
# 4.1 GB of shared sequences and bags, the ASan build alone is 4.7 GB).
section() {
  local free
  free=$(df -h --output=avail . | tail -1 | tr -d ' ')
  printf '\n==== %s (%s, %s free)\n' "$1" "$(date +%T)" "$free"
}

section "release build and tests"
build build all -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON
ctest --test-dir build --output-on-failure -j "$test_jobs" --timeout 900
[ "${1:-}" = "--quick" ] && exit 0

# The sanitizer runs read the synthetic sequences the release run rendered instead of rendering
# them again, 5-10 times slower (tests/test_support.hpp, sharedSynthetic), and the maps its
# program made for the tests that read a saved map (tests/session_runs.hpp, sharedMap: fr1/rpy
# mapped under ThreadSanitizer took 70 s in each of the session stream's tests).
export RGBDMAP_TEST_SYNTHETIC_DIR="$root/build/tests/tmp/synthetic"
export RGBDMAP_TEST_MAPPER="$root/build/rgbdmap"

section "ThreadSanitizer: threaded tests"
# No ROS here: its tests stop on reports inside uninstrumented roscpp (docs/testing.md).
build build-tsan threaded_tests "${sanitized[@]}" -DRGBDMAP_SANITIZE=thread -DRGBDMAP_WITH_ROS=OFF
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$root/tests/tsan.supp" \
  ctest --test-dir build-tsan --output-on-failure -j "$test_jobs" -L threads -LE long --timeout 1800
# Its gigabytes of instrumented programs go before the next build makes as many: CI machines'
# disks can be small (a run stopped on a full disk linking the last ASan program).
# RGBDMAP_KEEP_BUILDS=1 keeps it for a later incremental run.
[ "${RGBDMAP_KEEP_BUILDS:-}" = 1 ] || rm -rf build-tsan

section "AddressSanitizer + UBSan: the tests not threaded, but the long ones"
# At -O1: the ASan build from scratch took 9.6 min (18-20 at -O2 when last measured so,
# 2026-12-02; the largest unity file 72 s against 102), its tests 666 s against 580 (2026-12-07,
# 2 cores, nothing beside).
build build-asan asan_tests "${sanitized[@]}" -DRGBDMAP_SANITIZE=address \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
export UBSAN_OPTIONS="print_stacktrace=1 halt_on_error=1"
# LeakSanitizer's tracer, which stops every thread at exit to look for leaks, sometimes crashes
# after a test has passed ("Tracer caught signal 11", google/sanitizers#1353; once in CI on
# 2026-12-06). When the log shows that crash, the failed tests run once more: a test that failed
# for its own reasons fails again.
asan_log=build-asan/asan-tests.log
leak_checked() {
  ASAN_OPTIONS="detect_leaks=1 abort_on_error=1" \
    LSAN_OPTIONS="suppressions=$root/tests/lsan.supp print_suppressions=0" \
    ctest --test-dir build-asan --output-on-failure -j "$test_jobs" --timeout 1800 "$@"
}
if ! leak_checked -LE "^threads|ros|scale|long" 2>&1 | tee "$asan_log"; then
  grep -q "LeakSanitizer has encountered a fatal error" "$asan_log" || exit 1
  echo "LeakSanitizer's tracer crashed: the failed tests once more"
  leak_checked --rerun-failed
fi
# Programs that load OpenNI2's drivers, and the ROS tests but those of the node and merger on a
# master (roscpp, rosbag and their Python tools keep global state to exit, allocated in
# uninstrumented libraries): memory errors and UB still stop them, leaks are not checked.
ASAN_OPTIONS="detect_leaks=0 abort_on_error=1" \
  ctest --test-dir build-asan --output-on-failure -j "$test_jobs" --timeout 1800 -L "openni2|ros" -LE "long|master"
section "all test runs passed"
