#include "rgbdmap/config/run_options.hpp"

namespace rgbdmap {

Keys replayKeys(ReplayOptions& o) {
  return {
      number(
          "replay.rate", &o.rate, 0, 1000,
          "replay speed: 1 = as recorded (late frames dropped), 0 = as fast as possible, lossless"),
  };
}

Keys queueKeys(QueueOptions& o) {
  return {
      integer("queue.capacity", &o.capacity, 1, 1024, "frames queued between capture and mapping"),
  };
}

Keys checkpointKeys(CheckpointOptions& o) {
  return {
      integer("checkpoint.every_keyframes", &o.every_keyframes, 0, 100000000,
              "write a checkpoint every this many keyframes (0 = off)"),
      number("checkpoint.every_seconds", &o.every_seconds, 0, 1e9,
             "write a checkpoint every this many seconds (0 = off)"),
      number("checkpoint.min_seconds", &o.min_seconds, 0, 1e9,
             "checkpoints by keyframe count wait this long after the previous one (each extracts "
             "the whole map: every frame a keyframe, 50 keyframes would do it every 2 s)"),
      boolean("checkpoint.store", &o.store,
              "checkpoints write what changed in the map since the last one to MAP.store/ "
              "(rgbdmap export makes a PCD of it) and the whole MAP.pcd only at the end and on "
              "SIGUSR1 or a camera outage; false: every checkpoint rewrites MAP.pcd"),
      boolean("checkpoint.session", &o.session,
              "with loop closure: save the session (places, pose graph, kept keyframes) as "
              "MAP.session/ with every save, so that a later run can go on from it"),
  };
}

}  // namespace rgbdmap
