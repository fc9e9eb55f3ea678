#pragma once

#include "rgbdmap/base/option_keys.hpp"

namespace rgbdmap {

// How a recording is replayed (config section "replay"); the sources pace themselves by it.
struct ReplayOptions {
  double rate = 1.0;  // 1 = recorded speed, 0 = as fast as possible (lossless)
};

// The frame queue between the capture and the tracking thread (config section "queue").
struct QueueOptions {
  int capacity = 8;
};

// When the tracking thread writes checkpoints of the map (config section "checkpoint").
struct CheckpointOptions {
  int every_keyframes = 50;   // 0 = off
  double every_seconds = 60;  // 0 = off
  double min_seconds = 10;    // between checkpoints by keyframe count
  bool session = true;        // MAP.session/ with every save (with loop closure)
  bool store = true;          // MAP.store/ with every save; MAP.pcd then at the end and on request
};

Keys replayKeys(ReplayOptions& o);
Keys queueKeys(QueueOptions& o);
Keys checkpointKeys(CheckpointOptions& o);

}  // namespace rgbdmap
