#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/base/skip_reasons.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/mapping/keyframe_selector.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/runtime/output_files.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/slam/localiser.hpp"
#include "rgbdmap/slam/loop_closer.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

// Localising or continuing: which frames were tracked before the saved map was recognised. A
// frame counts when its keyframe (anchor) comes before the keyframe the first placement was made
// at, so the count is the same in every replay, however far tracking runs ahead of the loop
// thread. Frames are recorded by anchor only until tracking sees the first placement (bounded
// memory).
class FramesBeforePlacement {
 public:
  explicit FramesBeforePlacement(const PoseCorrections& placement) : placement_(placement) {}

  // Tracking thread, for every frame with a pose.
  void add(std::int64_t anchor);
  // After tracking and the loop thread have finished: the frames anchored before `first_placed`
  // (-1: never placed, every frame).
  std::uint64_t count(std::int64_t first_placed) const;

 private:
  const PoseCorrections& placement_;
  mutable std::mutex mutex_;
  bool placed_seen_ = false;
  std::uint64_t frames_ = 0;
  std::vector<std::uint64_t> by_anchor_;  // [0]: no anchor, [k + 1]: anchor k
};

// A run's loop thread as its mode makes it: loop closure (LoopCloser) or the localiser takes the
// tracker's keyframes and publishes the corrections that move the trajectories, the map and the
// poses shown. None of it without keyframes to close loops on (ground-truth poses) or with loop
// closure off.
struct LoopThread {
  std::unique_ptr<PoseCorrections> corrections;  // null: poses are never corrected
  std::unique_ptr<LoopCloser> loop_closer;
  std::unique_ptr<Localiser> localiser;
  // Continuing or localising: the frames tracked before the saved map was recognised.
  std::unique_ptr<FramesBeforePlacement> before_placement;

  // Where the tracker hands its keyframes (null: nowhere).
  KeyframeSink* keyframeSink() const;
  // What moves the poses shown (the viewer, ROS): the corrections when something is shown, and
  // always when localising (the poses are the saved map's frame's); null: shown as tracked.
  const PoseCorrections* shownPoses(bool shown) const;
  // Every keyframe searched or looked for: the corrections are final.
  void finish();
};

// A run's mode: mapping from nothing, continuing a saved session, or localising in one. It says
// what the run loads, what its loop thread does, what it writes and how it ends; the pipeline and
// the front doors ask it instead of testing flags. Made by chooseRunMode (below).
class RunMode {
 public:
  virtual ~RunMode() = default;

  // "mapping", "continuing PATH", "localising in PATH" (the log).
  virtual std::string name() const = 0;

  // What it loads: the saved session it starts from (null: none).
  const std::shared_ptr<const Session>& saved() const { return saved_; }
  // What it writes: whether it makes a map (and a mesh, grid, OctoMap, session) at all, and the
  // files of a run whose map is `map_path` (--out, ~out) and mesh `mesh_path` ("" = none).
  virtual bool maps() const { return true; }
  virtual PipelineOutputs outputs(const std::string& map_path, const std::string& mesh_path) const;

  // What its loop thread does, for a run configured by `config` (lossless: a replay at --rate
  // max, whose loop thread never skips a keyframe).
  virtual LoopThread startLoopThread(const Config& config, RunStats& stats, bool lossless) const;
  // Which frames become keyframes (localising: none, nothing is mapped).
  virtual KeyframeSelector keyframeSelector(const Config& config) const;
  // What the map holds before the first frame (continuing: the saved keyframes, fused once the
  // run joins the saved map).
  virtual void startMap(Mapper& mapper) const;
  // What the trajectories hold before the first frame (continuing: the saved runs' frames and
  // fused keyframes, which the one graph corrects from the join on); null: not written.
  virtual void startTrajectories(PoseSink* frames, PoseSink* keyframes) const;
  // How the run poses and maps, for the log (`poses`: the pose provider's description).
  virtual std::string describe(const std::string& poses, const Config& config,
                               const LoopThread& loop) const = 0;

  // How the run ends: says what became of it and returns the exit code that calls for, 0 or 1
  // (the saved map never recognised, nothing mapped). `skipped`: the source's reasons for the
  // frames it could not use; `stopped_on_request`: a stop ended the run (no failure).
  virtual int end(const LoopThread& loop, RunStats& stats,
                  const std::vector<SkipReasons::Entry>& skipped,
                  bool stopped_on_request) const = 0;

 protected:
  RunMode() = default;
  explicit RunMode(std::shared_ptr<const Session> saved) : saved_(std::move(saved)) {}

 private:
  std::shared_ptr<const Session> saved_;
};

// A map from nothing, with loop closure when the poses have keyframes and loop.enabled is set.
class MapFromNothing : public RunMode {
 public:
  std::string name() const override { return "mapping"; }
  std::string describe(const std::string& poses, const Config& config,
                       const LoopThread& loop) const override;
  int end(const LoopThread& loop, RunStats& stats, const std::vector<SkipReasons::Entry>& skipped,
          bool stopped_on_request) const override;
};

// Goes on from a saved session (--continue): maps in the run's own frame until loop closure
// recognises the saved map, then in the saved map's, and writes one map and one session of both.
class ContinueSession : public RunMode {
 public:
  ContinueSession(std::shared_ptr<const Session> saved, std::string path)
      : RunMode(std::move(saved)), path_(std::move(path)) {}
  std::string name() const override { return "continuing " + path_; }
  LoopThread startLoopThread(const Config& config, RunStats& stats, bool lossless) const override;
  void startMap(Mapper& mapper) const override;
  void startTrajectories(PoseSink* frames, PoseSink* keyframes) const override;
  std::string describe(const std::string& poses, const Config& config,
                       const LoopThread& loop) const override;
  int end(const LoopThread& loop, RunStats& stats, const std::vector<SkipReasons::Entry>& skipped,
          bool stopped_on_request) const override;

 private:
  std::string path_;
};

// Poses every frame in a saved session's map (--localise): nothing is fused and no map is
// written, only the trajectory of every frame (in the saved map's frame once it is recognised)
// and the configuration.
class LocaliseInSession : public RunMode {
 public:
  LocaliseInSession(std::shared_ptr<const Session> saved, std::string path)
      : RunMode(std::move(saved)), path_(std::move(path)) {}
  std::string name() const override { return "localising in " + path_; }
  bool maps() const override { return false; }
  PipelineOutputs outputs(const std::string& map_path, const std::string& mesh_path) const override;
  LoopThread startLoopThread(const Config& config, RunStats& stats, bool lossless) const override;
  KeyframeSelector keyframeSelector(const Config& config) const override;
  std::string describe(const std::string& poses, const Config& config,
                       const LoopThread& loop) const override;
  int end(const LoopThread& loop, RunStats& stats, const std::vector<SkipReasons::Entry>& skipped,
          bool stopped_on_request) const override;

 private:
  std::string path_;
};

// What a front door was asked for: its map, a saved session to localise in or to continue
// ("" = none; not both), and whether a mesh, a grid or an OctoMap was asked for.
struct RunRequest {
  std::string out;
  std::string localise;
  std::string continue_from;
  bool mesh = false, grid = false, octomap = false;
};

// How a front door names its options and config keys in a refusal: the CLI "--out",
// "--localise a.session", `--set pose.source=odometry`; the node "~out",
// "parameter /rgbdmap/localise", `_pose/source:=odometry`.
struct OptionNames {
  std::string out;                      // the map's option
  std::string localise, continue_from;  // the options that name the saved session, as given
  std::string mesh, grid, octomap;      // "" where the door has no such option
  // A config key as its users write it, and how they set one.
  std::function<std::string(const std::string& key)> key;
  std::function<std::string(const std::string& key, const std::string& value)> set;
};

// The run's mode for `request`, every refusal of the front doors in one place. A saved session
// needs the camera's own motion (pose.source "auto" becomes "odometry" in `config`, and a pose
// source without keyframes is refused); continuing needs loop closure; localising maps nothing
// (no mesh, grid or OctoMap), a continued session keeps no free space (no OctoMap), and the run's
// files must not land beside the saved map's. Then the session is read (localising keeps only its
// graph and places). Throws InputError naming the option as `names` spells it.
std::shared_ptr<const RunMode> chooseRunMode(const RunRequest& request, Config& config,
                                             const OptionNames& names);

}  // namespace rgbdmap
