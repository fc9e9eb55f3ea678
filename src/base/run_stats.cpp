#include "rgbdmap/base/run_stats.hpp"

#include <malloc.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace rgbdmap {
namespace {

constexpr double kMinSeconds = 1e-6;
constexpr double kBinsPerDecade = 100.0;

// `text` as a JSON string (control characters, which no message of ours holds, left out).
std::string jsonString(const std::string& text) {
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) quoted += c;
  }
  return quoted + "\"";
}

}  // namespace

void LatencyHistogram::record(double seconds) {
  const double clamped = std::max(seconds, kMinSeconds);
  int bin = static_cast<int>(std::log10(clamped / kMinSeconds) * kBinsPerDecade);
  bin = std::min(std::max(bin, 0), kBins - 1);
  ++bins_[bin];
  ++count_;
  sum_ += seconds;
  max_ = std::max(max_, seconds);
}

double LatencyHistogram::percentile(double q) const {
  if (count_ == 0) return 0.0;
  const auto target = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (int bin = 0; bin < kBins; ++bin) {
    seen += bins_[bin];
    if (seen >= std::max<std::uint64_t>(target, 1))
      return std::min(max_, kMinSeconds * std::pow(10.0, (bin + 0.5) / kBinsPerDecade));
  }
  return max_;
}

std::string RunStats::toJson() const {
  std::ostringstream out;
  out.precision(6);
  auto latency = [&](const char* name, const LatencyHistogram& h, bool last) {
    out << "    \"" << name << "\": {\"count\": " << h.count()
        << ", \"mean_ms\": " << h.mean() * 1e3 << ", \"p50_ms\": " << h.percentile(0.5) * 1e3
        << ", \"p90_ms\": " << h.percentile(0.9) * 1e3
        << ", \"p95_ms\": " << h.percentile(0.95) * 1e3
        << ", \"p99_ms\": " << h.percentile(0.99) * 1e3 << ", \"max_ms\": " << h.max() * 1e3 << "}"
        << (last ? "\n" : ",\n");
  };
  out << "{\n"
      << "  \"frames_captured\": " << frames_captured << ",\n"
      << "  \"frames_skipped\": " << frames_skipped << ",\n"
      << "  \"frames_dropped\": " << frames_dropped << ",\n"
      << "  \"frames_processed\": " << frames_processed << ",\n"
      << "  \"frames_without_pose\": " << frames_without_pose << ",\n"
      << "  \"keyframes\": " << keyframes << ",\n"
      << "  \"map_points\": " << map_points << ",\n"
      << "  \"checkpoints_written\": " << checkpoints_written << ",\n"
      << "  \"checkpoints_failed\": " << checkpoints_failed << ",\n"
      << "  \"store_bytes_written\": " << store_bytes_written << ",\n"
      << "  \"disconnects\": " << disconnects << ",\n"
      << "  \"frames_tracked\": " << frames_tracked << ",\n"
      << "  \"frames_lost\": " << frames_lost << ",\n"
      << "  \"frames_relocalised\": " << frames_relocalised << ",\n"
      << "  \"frames_unplaced\": " << frames_unplaced << ",\n"
      << "  \"localising\": " << (localising ? "true" : "false") << ",\n"
      << "  \"keyframes_looked_for\": " << keyframes_looked_for << ",\n"
      << "  \"keyframes_placed\": " << keyframes_placed << ",\n"
      << "  \"keyframes_deferred\": " << keyframes_deferred << ",\n"
      << "  \"loop_closure\": " << (loop_closure ? "true" : "false") << ",\n"
      << "  \"loop_candidates\": " << loop_candidates << ",\n"
      << "  \"loops_verified\": " << loops_verified << ",\n"
      << "  \"loops_accepted\": " << loops_accepted << ",\n"
      << "  \"loops_rejected\": " << loops_rejected << ",\n"
      << "  \"loop_keyframes_unsearched\": " << loop_keyframes_unsearched << ",\n"
      << "  \"floor_observations\": " << floor_observations << ",\n"
      << "  \"map_refusions\": " << map_refusions << ",\n"
      << "  \"region_refusions\": " << region_refusions << ",\n"
      << "  \"keyframes_refused\": " << keyframes_refused << ",\n"
      << "  \"wall_seconds\": " << wall_seconds << ",\n"
      << "  \"frames_per_second\": "
      << (wall_seconds > 0 ? static_cast<double>(frames_processed) / wall_seconds : 0.0) << ",\n"
      << "  \"peak_rss_mb\": " << peak_rss_mb << ",\n"
      << "  \"mesh_triangles\": " << mesh_triangles << ",\n"
      << "  \"map_memory_mb\": " << map_memory_mb << ",\n"
      << "  \"kept_keyframes_mb\": " << kept_keyframes_mb << ",\n"
      << "  \"kept_keyframes_on_disk\": " << kept_keyframes_on_disk << ",\n"
      << "  \"kept_keyframes_disk_mb\": " << kept_keyframes_disk_mb << ",\n"
      << "  \"map_blocks_stored\": " << map_blocks_stored << ",\n"
      << "  \"map_blocks_on_disk\": " << map_blocks_on_disk << ",\n"
      << "  \"map_disk_mb\": " << map_disk_mb << ",\n"
      << "  \"place_database_mb\": " << place_database_mb << ",\n"
      << "  \"ground\": " << jsonString(ground) << ",\n"
      << "  \"latency\": {\n";
  latency("read", read_latency, false);
  latency("queue_wait", queue_latency, false);
  latency("pose", pose_latency, false);
  latency("track", track_latency, false);
  latency("filter", filter_latency, false);
  latency("project", project_latency, false);
  latency("fuse", fuse_latency, false);
  latency("integrate", integrate_latency, false);
  latency("loop", loop_latency, false);
  latency("optimise", optimise_latency, false);
  latency("refuse", refuse_latency, false);
  latency("mesh_extract", mesh_extract_latency, false);
  latency("mesh_write", mesh_write_latency, false);
  latency("grid_write", grid_write_latency, false);
  latency("octomap_write", octomap_write_latency, false);
  latency("store_write", store_write_latency, true);
  out << "  }\n}\n";
  return out.str();
}

double peakRssMb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0.0;
}

void tuneAllocator() {
#if defined(__GLIBC__)
  ::mallopt(M_MMAP_THRESHOLD, 512 * 1024);
  ::mallopt(M_ARENA_MAX, 2);
#endif
}

void releaseFreedMemory() {
#if defined(__GLIBC__)
  ::malloc_trim(0);
#endif
}

}  // namespace rgbdmap
