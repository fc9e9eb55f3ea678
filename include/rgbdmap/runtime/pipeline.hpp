#pragma once

#include <memory>
#include <string>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/frame_source.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/runtime/map_publisher.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/runtime/run_thread.hpp"

namespace rgbdmap {

class RunMode;

// The running system: a capture thread reads the source into a bounded queue, a tracking thread
// gives every frame its pose, picks keyframes and triggers checkpoints, a fusion thread fuses the
// keyframes into the map and takes its snapshots, a writer thread writes them; the loop thread
// (loop closure or the localiser) is the run's mode's. run() returns after the source ends or a
// stop is requested, with the final map written.
class Pipeline {
 public:
  // `mode`: mapping from nothing, continuing a saved session or localising in one (run_mode.hpp);
  // `outputs` as the mode names them (RunMode::outputs).
  Pipeline(Config config, std::unique_ptr<FrameSource> source, PipelineOutputs outputs,
           std::shared_ptr<const RunMode> mode);

  // Returns the process exit code: 0 on success, 1 when the run stopped on bad input or a failed
  // final write (the map built so far is still saved) or its mode's end calls for it.
  int run(RunControl& control);
  const RunStats& stats() const { return stats_; }

 private:
  Config config_;
  std::unique_ptr<FrameSource> source_;
  PipelineOutputs outputs_;
  std::shared_ptr<const RunMode> mode_;
  RunStats stats_;
};

}  // namespace rgbdmap
