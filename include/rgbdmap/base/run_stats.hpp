#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

namespace rgbdmap {

// Latency distribution in fixed logarithmic bins (1 µs .. ~100 s), so recording a sample never
// allocates. Percentiles are accurate to the bin width (~2.3%). Written by one thread.
class LatencyHistogram {
 public:
  void record(double seconds);
  double percentile(double q) const;  // q in [0, 1]; seconds; 0 when empty
  std::uint64_t count() const { return count_; }
  double mean() const { return count_ ? sum_ / static_cast<double>(count_) : 0.0; }
  double max() const { return max_; }

 private:
  static constexpr int kBins = 800;
  std::array<std::uint64_t, kBins> bins_{};
  std::uint64_t count_ = 0;
  double sum_ = 0.0;
  double max_ = 0.0;
};

// Counters shared by the capture, mapping and status threads (atomics), and per-stage latency
// histograms each written by one thread (read only after the threads have stopped).
struct RunStats {
  std::atomic<std::uint64_t> frames_captured{0};   // delivered by the source
  std::atomic<std::uint64_t> frames_skipped{0};    // unusable captures (bad image, size)
  std::atomic<std::uint64_t> frames_dropped{0};    // discarded because mapping fell behind
  std::atomic<std::uint64_t> frames_processed{0};  // taken by the mapping thread
  std::atomic<std::uint64_t> frames_without_pose{0};
  std::atomic<std::uint64_t> keyframes{0};
  std::atomic<std::uint64_t> map_points{0};
  std::atomic<std::uint64_t> map_bytes{0};          // Mapper::memoryBytes(), after each keyframe
  std::atomic<std::uint64_t> map_blocks_stored{0};  // TSDF blocks moved to disk (map.memory)
  std::atomic<std::uint64_t> place_bytes{0};        // loop closure's place database
  std::atomic<std::uint64_t> checkpoints_written{0};
  std::atomic<std::uint64_t> checkpoints_failed{0};
  std::atomic<std::uint64_t> store_bytes_written{0};  // to the map store, all saves together
  std::atomic<std::uint64_t> queue_depth{0};
  std::atomic<std::uint64_t> disconnects{0};
  // Tracking, per frame: a pose good to map, tracking failed (the frame keeps the predicted pose
  // in the trajectory and is not mapped), recovered after a loss.
  std::atomic<std::uint64_t> frames_tracked{0};
  std::atomic<std::uint64_t> frames_lost{0};
  std::atomic<std::uint64_t> frames_relocalised{0};
  // Localising (--localise): frames posed before the saved map was recognised, keyframes looked
  // for among the saved places and placements taken.
  std::atomic<std::uint64_t> frames_unplaced{0};
  std::atomic<std::uint64_t> keyframes_looked_for{0};
  std::atomic<std::uint64_t> keyframes_placed{0};
  // Keyframes proposed while every fusion slot was busy (live sources): the next frame is
  // proposed instead, nothing is dropped.
  std::atomic<std::uint64_t> keyframes_deferred{0};
  std::atomic<bool> tracking_lost{false};  // the last frame was lost (status line)
  // Loop closure: earlier keyframes that looked like the newest one and were checked
  // geometrically, those that passed, loops accepted into the pose graph, loops refused
  // (implausible, no second loop agreed, or the optimised graph disagreed), and keyframes a
  // busy loop thread could not search (live sources only).
  std::atomic<std::uint64_t> loop_candidates{0};
  std::atomic<std::uint64_t> loops_verified{0};
  std::atomic<std::uint64_t> loops_accepted{0};
  std::atomic<std::uint64_t> loops_rejected{0};
  std::atomic<std::uint64_t> loop_keyframes_unsearched{0};
  // Keyframes whose view of the floor tied them to it in the pose graph (loop.floor).
  std::atomic<std::uint64_t> floor_observations{0};
  // With loop closure: times the map was fused again from the kept keyframes to follow a loop
  // (of which region passes: only where the loop moved it), and keyframes fused again in all.
  std::atomic<std::uint64_t> map_refusions{0};
  std::atomic<std::uint64_t> region_refusions{0};
  std::atomic<std::uint64_t> keyframes_refused{0};
  bool loop_closure = false;  // the run closes loops (set before the threads start)
  bool localising = false;    // the run localises in a saved map (set before the threads start)

  LatencyHistogram read_latency;       // capture: read + decode + convert
  LatencyHistogram filter_latency;     // mapping: depth filtering
  LatencyHistogram project_latency;    // back-projection (+ statistical filter when enabled)
  LatencyHistogram fuse_latency;       // voxel fusion
  LatencyHistogram integrate_latency;  // whole keyframe integration
  LatencyHistogram pose_latency;       // pose estimation
  LatencyHistogram track_latency;      // tracking thread, per frame: pose, keyframe?, hand-off
  LatencyHistogram queue_latency;      // capture-to-mapping: time a frame waited in the queue
  LatencyHistogram loop_latency;       // loop thread, per keyframe: graph, place recognition
  LatencyHistogram optimise_latency;   // pose graph optimisation, per accepted loop closure
  LatencyHistogram refuse_latency;     // fusion thread, per step of re-fusion (a few keyframes)
  // --mesh only: marching cubes per map save (fusion thread, then the final save), and writing
  // the PLY (writer thread).
  LatencyHistogram mesh_extract_latency;
  LatencyHistogram mesh_write_latency;
  LatencyHistogram grid_write_latency;     // floor found, grid drawn and written (writer thread)
  LatencyHistogram octomap_write_latency;  // OctoMap built and written (writer thread)
  LatencyHistogram store_write_latency;    // the map's changes to its store (writer thread)
  std::atomic<std::uint64_t> mesh_triangles{0};  // in the last mesh written
  double map_memory_mb = 0.0;      // the map at the end: TSDF blocks and index, kept keyframes
  double kept_keyframes_mb = 0.0;  // of which the kept keyframes' images (loop closure)
  // Kept keyframes whose images went to disk (beyond loop.keyframe_memory), and their bytes.
  std::uint64_t kept_keyframes_on_disk = 0;
  double kept_keyframes_disk_mb = 0.0;
  // TSDF blocks on disk at the end (beyond map.memory), and their scratch files' size.
  std::uint64_t map_blocks_on_disk = 0;
  double map_disk_mb = 0.0;
  double place_database_mb = 0.0;  // loop closure's places (ORB features, dense references)
  // Where up and the floor of the final map came from (--grid; "" without): the log says it
  // when its sources change, which a slow run may do at a checkpoint of part of the map.
  std::string ground;

  double wall_seconds = 0.0;
  double peak_rss_mb = 0.0;

  std::string toJson() const;
};

// Peak resident set size of this process in MB (VmHWM), 0 if unknown.
double peakRssMb();
// Hands memory the process has freed back to the system. The C library keeps freed memory for
// reuse, scattered over its per-thread arenas; a long run that frees and allocates as it goes
// (loop closure's optimisations, re-fusion) otherwise creeps up in resident memory it is not
// using.
void releaseFreedMemory();
// Sets the C library's allocator up for a long run, before any thread starts: buffers of 512 KB
// and more (images, pyramids, a snapshot's cloud) are mapped on their own and returned the
// moment they are freed, instead of the threshold rising to the largest freed buffer and those
// buffers scattering over the heap; and two arenas instead of eight per core, so that memory one
// thread frees another can reuse. On 10 laps of a room the highest RSS per lap fell from 377-398
// to 363-377 MB and the peak from 403 to 379 MB (docs/loop-closure.md).
void tuneAllocator();

}  // namespace rgbdmap
