#include "rgbdmap/runtime/status_line.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <thread>

namespace rgbdmap {
namespace {

// Memory the threads freed is handed back to the system this often (s): it costs a walk over the
// heap, and a long run would otherwise keep what it freed (releaseFreedMemory()).
constexpr double kReleaseEvery = 5.0;

double megabytes(const std::atomic<std::uint64_t>& bytes) {
  return static_cast<double>(bytes.load()) / (1024.0 * 1024.0);
}

// " | loops N, places X MB" while loop closure runs (the status line says when a loop closed).
// or " | placed N of M keyframes" while localising in a saved map.
std::string loops(const RunStats& s) {
  char text[64];
  if (s.localising) {
    std::snprintf(text, sizeof text, " | placed %llu of %llu keyframes",
                  static_cast<unsigned long long>(s.keyframes_placed.load()),
                  static_cast<unsigned long long>(s.keyframes_looked_for.load()));
    return text;
  }
  if (!s.loop_closure) return "";
  std::snprintf(text, sizeof text, " | loops %llu, places %.1f MB",
                static_cast<unsigned long long>(s.loops_accepted.load()), megabytes(s.place_bytes));
  return text;
}

std::string statusLine(const RunStats& s, double elapsed) {
  char line[256];
  std::snprintf(line, sizeof line,
                "frames %llu read, %llu dropped, %llu skipped | %.1f fps | keyframes %llu | map "
                "%llu points, %.0f MB | queue %llu%s%s",
                static_cast<unsigned long long>(s.frames_captured.load()),
                static_cast<unsigned long long>(s.frames_dropped.load()),
                static_cast<unsigned long long>(s.frames_skipped.load()),
                elapsed > 0 ? static_cast<double>(s.frames_processed.load()) / elapsed : 0.0,
                static_cast<unsigned long long>(s.keyframes.load()),
                static_cast<unsigned long long>(s.map_points.load()), megabytes(s.map_bytes),
                static_cast<unsigned long long>(s.queue_depth.load()), loops(s).c_str(),
                s.tracking_lost.load() ? " | tracking lost" : "");
  return line;
}

}  // namespace

StatusLine::StatusLine(RunStats& stats, const FrameQueue& queue, bool enabled,
                       Clock::time_point start)
    : stats_(stats),
      queue_(queue),
      enabled_(enabled),
      tty_(enabled && ::isatty(STDERR_FILENO)),
      start_(start) {}

void StatusLine::showUntil(const std::function<bool()>& done, const std::atomic<bool>& stop) {
  double last_print = 0, last_release = 0;
  bool stop_announced = false;
  while (!done()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stats_.queue_depth.store(queue_.depth());
    if (stop.load() && !stop_announced) {
      stop_announced = true;
      if (tty_) std::fputc('\n', stderr);
      spdlog::info("stopping: draining {} queued frames, then saving", queue_.depth());
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    if (elapsed - last_release >= kReleaseEvery) {
      last_release = elapsed;
      releaseFreedMemory();
    }
    if (enabled_ && elapsed - last_print >= (tty_ ? 0.25 : 5.0)) {
      last_print = elapsed;
      if (tty_)
        std::fprintf(stderr, "\r%s\033[K", statusLine(stats_, elapsed).c_str());
      else
        spdlog::info("{}", statusLine(stats_, elapsed));
    }
  }
}

void StatusLine::showFinal(double wall_seconds) const {
  if (tty_) std::fprintf(stderr, "\r%s\033[K\n", statusLine(stats_, wall_seconds).c_str());
}

}  // namespace rgbdmap
