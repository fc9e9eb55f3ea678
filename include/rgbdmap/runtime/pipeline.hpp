#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/frame_source.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/runtime/map_publisher.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/runtime/run_thread.hpp"

namespace rgbdmap {

struct Session;

// The running system: a capture thread reads the source into a bounded queue, a tracking thread
// gives every frame its pose, picks keyframes and triggers checkpoints, a fusion thread fuses the
// keyframes into the map and takes its snapshots, a writer thread writes them. run() returns
// after the source ends or a stop is requested, with the final map written.
class Pipeline {
 public:
  // `saved`: a saved session the run starts from, used as `use` says:
  // - kLocalise (--localise): every frame is posed in the saved map's frame (trajectories,
  //   viewer, ROS), nothing is fused and no map is written (leave outputs.map_path empty);
  // - kContinue (--continue): the run maps in its own frame until it recognises the saved map,
  //   then in the saved map's, and writes one map and one session of both (LoopCloser, Mapper).
  // Either way frames posed before the saved map is recognised are counted.
  enum class SessionUse { kLocalise, kContinue };
  Pipeline(Config config, std::unique_ptr<FrameSource> source, PipelineOutputs outputs,
           std::shared_ptr<const Session> saved = nullptr, SessionUse use = SessionUse::kLocalise);

  // Returns the process exit code: 0 on success, 1 when the run stopped on bad input or a failed
  // final write (the map built so far is still saved).
  int run(RunControl& control);
  const RunStats& stats() const { return stats_; }

 private:
  Config config_;
  std::unique_ptr<FrameSource> source_;
  PipelineOutputs outputs_;
  std::shared_ptr<const Session> saved_;
  SessionUse use_;
  RunStats stats_;
};

}  // namespace rgbdmap
