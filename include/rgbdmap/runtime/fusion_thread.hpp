#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/runtime/frame_queue.hpp"

namespace rgbdmap {

// Fuses keyframes into the map on its own thread, so that tracking (the thread that submits
// them) never waits for a slow keyframe. A keyframe is copied into one of a few preallocated
// slots, so the capture pool's frame goes back at once and steady state allocates nothing;
// keyframes are fused one at a time in the order submitted, so a lossless replay gives the same
// map every time. Map snapshots (checkpoints) are taken here too, between two keyframes: the
// tracking thread only asks for one.
// What a map request is for. Each kind has its own slot, so a viewer's request never replaces a
// pending checkpoint.
enum class MapRequest { kCheckpoint, kViewer };

class FusionThread {
 public:
  using ErrorHandler = std::function<void(const std::string&)>;
  using MapTask = std::function<void(const Mapper&)>;
  // Gives the corrections a keyframe is fused at; called on the fusion thread when the keyframe's
  // turn comes, and may wait there.
  using Settled = std::function<PoseCorrections::Snapshot()>;

  // `slots`: keyframes that may wait for fusion (plus the one being fused); images are
  // width x height.
  FusionThread(Mapper& mapper, std::size_t slots, int width, int height, ErrorHandler on_error);
  ~FusionThread();  // finish()

  // Hands a keyframe over. With `wait`, blocks until a slot is free (replay: lossless and
  // deterministic); without, returns false at once when every slot is busy (live: the caller
  // proposes a later frame instead).
  // `at`: the corrections to fuse it at (a lossless replay's, see Mapper::fuse); a fusion thread
  // given them does not follow loops while idle either (how much it did would depend on timing),
  // only a few kept keyframes per keyframe fused (RefusionOptions::refusion_pace).
  bool submit(const Frame& keyframe, bool wait, Settled at = nullptr);
  // Runs `task` on the fusion thread with the map between two keyframes (e.g. to take a
  // checkpoint snapshot). A request not yet served is replaced by a newer one of the same kind.
  void request(MapRequest kind, MapTask task);
  // Fuses every submitted keyframe, then stops the thread. A request not served by then is
  // dropped (the caller's final save follows). After this, the Mapper is the caller's again.
  void finish();
  std::size_t queued() const { return keyframes_.depth(); }

 private:
  void run();
  void serveRequest();

  Mapper& mapper_;
  FrameQueue keyframes_;
  ErrorHandler on_error_;
  std::mutex request_mutex_;        // taken only when a request is made or served
  std::array<MapTask, 2> pending_;  // by MapRequest
  std::atomic<bool> requested_{false};
  std::mutex pinned_mutex_;
  std::unordered_map<const Frame*, Settled> pinned_;  // by queued slot
  std::atomic<bool> follows_while_idle_{true};
  std::thread thread_;
};

}  // namespace rgbdmap
