#include "rgbdmap/runtime/run_mode.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/runtime/unmapped_frames.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"

namespace rgbdmap {

void FramesBeforePlacement::add(std::int64_t anchor) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frames_;
  if (placed_seen_) return;
  const PoseCorrections::Snapshot placement = placement_.snapshot();
  if (!placement.table->empty() && placement.joined) {
    placed_seen_ = true;  // later frames are anchored at or after the placement's keyframe
    return;
  }
  const auto slot = static_cast<std::size_t>(std::max<std::int64_t>(anchor, -1) + 1);
  if (by_anchor_.size() <= slot) by_anchor_.resize(slot + 1, 0);
  ++by_anchor_[slot];
}

std::uint64_t FramesBeforePlacement::count(std::int64_t first_placed) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (first_placed < 0) return frames_;
  std::uint64_t before = 0;
  const auto end = std::min(by_anchor_.size(), static_cast<std::size_t>(first_placed) + 1);
  for (std::size_t slot = 0; slot < end; ++slot) before += by_anchor_[slot];
  return before;
}

KeyframeSink* LoopThread::keyframeSink() const {
  return localiser ? static_cast<KeyframeSink*>(localiser.get()) : loop_closer.get();
}

const PoseCorrections* LoopThread::shownPoses(bool shown) const {
  return shown || localiser ? corrections.get() : nullptr;
}

void LoopThread::finish() {
  if (loop_closer) loop_closer->finish();  // every keyframe searched: final corrections
  if (localiser) localiser->finish();
}

namespace {

// Loop closure, going on from `continued` (a saved session's graph and places) when given; none
// without a tracker with keyframes (the dense one) or with loop.enabled off.
LoopThread loopClosure(const Config& config, RunStats& stats, bool lossless,
                       const LoopCloser::Saved* continued) {
  LoopThread loop;
  if (!config.loop.enabled || !tracksKeyframes(config.pose, config.tracking)) return loop;
  loop.corrections = std::make_unique<PoseCorrections>();
  loop.loop_closer = std::make_unique<LoopCloser>(config.camera, config.tracking, config.loop,
                                                  config.filter.min_depth, config.filter.max_depth,
                                                  *loop.corrections, stats, lossless, continued);
  return loop;
}

// Continuing and localising end by saying when the saved map was recognised; 1 when never.
int reportContinuation(const LoopCloser& loop_closer, const RunStats& stats) {
  if (loop_closer.joinedAt() < 0) {
    spdlog::error(
        "continuing: the saved map was never recognised ({} keyframes looked for): the map "
        "written is this run's own, in its own frame, and no session is saved (it would hold two "
        "maps in unrelated frames)",
        stats.keyframes_looked_for.load());
    return 1;
  }
  spdlog::info(
      "continuing: joined the saved map at keyframe {}; {} frames were tracked before it was "
      "recognised (written in its frame since)",
      loop_closer.joinedAt(), stats.frames_unplaced.load());
  return 0;
}

int reportLocalisation(const Localiser::Counts& counts, const RunStats& stats) {
  const std::uint64_t frames = stats.frames_processed.load();
  const std::uint64_t unplaced = stats.frames_unplaced.load();
  if (counts.first_placed < 0) {
    spdlog::error(
        "localisation: the saved map was never recognised ({} keyframes looked for); the {} "
        "frames' poses are written in the run's own frame",
        stats.keyframes_looked_for.load(), frames);
    return 1;
  }
  spdlog::info(
      "localisation: {} of {} frames placed in the saved map, {} tracked before it was recognised "
      "at keyframe {} (written in its frame since); {} placements of {} keyframes looked for{}",
      frames - std::min(frames, unplaced), frames, unplaced, counts.first_placed,
      stats.keyframes_placed.load(), stats.keyframes_looked_for.load(),
      counts.skipped > 0 ? fmt::format(", {} skipped behind the camera", counts.skipped) : "");
  return 0;
}

}  // namespace

PipelineOutputs RunMode::outputs(const std::string& map_path, const std::string& mesh_path) const {
  return outputsBeside(map_path, mesh_path);
}

LoopThread RunMode::startLoopThread(const Config& config, RunStats& stats, bool lossless) const {
  return loopClosure(config, stats, lossless, nullptr);
}

KeyframeSelector RunMode::keyframeSelector(const Config& config) const {
  return makeKeyframeSelector(config.keyframe, config.pose);
}

void RunMode::startMap(Mapper&) const {}

void RunMode::startTrajectories(PoseSink*, PoseSink*) const {}

std::string MapFromNothing::describe(const std::string& poses, const Config& config,
                                     const LoopThread& loop) const {
  return fmt::format("poses: {}, keyframes: {}, loop closure: {}", poses,
                     effectiveKeyframePolicy(config.keyframe, config.pose),
                     loop.loop_closer ? "on" : "off");
}

// Nothing mapped is a failure; most frames unused is worth saying.
int MapFromNothing::end(const LoopThread&, RunStats& stats,
                        const std::vector<SkipReasons::Entry>& skipped,
                        bool stopped_on_request) const {
  return UnmappedFrames::of(stats, skipped).report(stopped_on_request);
}

LoopThread ContinueSession::startLoopThread(const Config& config, RunStats& stats,
                                            bool lossless) const {
  LoopThread loop = loopClosure(config, stats, lossless, &saved()->graph);
  loop.before_placement = std::make_unique<FramesBeforePlacement>(*loop.corrections);
  return loop;
}

void ContinueSession::startMap(Mapper& mapper) const { mapper.continueFrom(saved()->keyframes); }

void ContinueSession::startTrajectories(PoseSink* frames, PoseSink* keyframes) const {
  for (const auto& [sink, poses] :
       {std::make_pair(frames, &saved()->frames), std::make_pair(keyframes, &saved()->fused)}) {
    if (!sink) continue;
    for (const AnchoredPose& p : *poses) {
      // (Anchored within the saved graph: the ids after it are this run's keyframes.)
      const AnchoredPose a = anchoredInGraph(*saved(), p);
      sink->record(a.timestamp, a.pose, a.anchor);
    }
  }
}

std::string ContinueSession::describe(const std::string& poses, const Config& config,
                                      const LoopThread&) const {
  return fmt::format(
      "poses: {}, keyframes: {}, continuing a saved map of {} keyframes: mapped in this run's "
      "own frame until a saved place is recognised, then in the saved map's",
      poses, effectiveKeyframePolicy(config.keyframe, config.pose),
      saved()->graph.keyframes.size());
}

int ContinueSession::end(const LoopThread& loop, RunStats& stats,
                         const std::vector<SkipReasons::Entry>& skipped,
                         bool stopped_on_request) const {
  stats.frames_unplaced.store(loop.before_placement->count(loop.loop_closer->joinedAt()));
  const int code = reportContinuation(*loop.loop_closer, stats);
  return std::max(code, UnmappedFrames::of(stats, skipped).report(stopped_on_request));
}

PipelineOutputs LocaliseInSession::outputs(const std::string& map_path, const std::string&) const {
  return localisationOutputs(map_path);
}

// The localiser publishes the corrections: every pose in the saved map's frame.
LoopThread LocaliseInSession::startLoopThread(const Config& config, RunStats& stats,
                                              bool lossless) const {
  LoopThread loop;
  loop.corrections = std::make_unique<PoseCorrections>();
  loop.localiser = std::make_unique<Localiser>(
      saved()->graph, config.camera, config.tracking, config.loop, config.filter.min_depth,
      config.filter.max_depth, *loop.corrections, stats, lossless);
  loop.before_placement = std::make_unique<FramesBeforePlacement>(*loop.corrections);
  return loop;
}

KeyframeSelector LocaliseInSession::keyframeSelector(const Config& config) const {
  return KeyframeSelector(KeyframeSelector::Policy::kNone, config.keyframe);
}

std::string LocaliseInSession::describe(const std::string& poses, const Config&,
                                        const LoopThread& loop) const {
  return fmt::format(
      "poses: {}, localising in a saved map of {} keyframes ({} places): nothing "
      "mapped",
      poses, saved()->graph.keyframes.size(), loop.localiser->places());
}

int LocaliseInSession::end(const LoopThread& loop, RunStats& stats,
                           const std::vector<SkipReasons::Entry>&, bool) const {
  const Localiser::Counts counts = loop.localiser->counts();
  stats.frames_unplaced.store(loop.before_placement->count(counts.first_placed));
  return reportLocalisation(counts, stats);
}

namespace {

// "a, b or c" of the names that are not empty.
std::string oneOf(const std::vector<std::string>& names) {
  std::vector<std::string> given;
  for (const std::string& n : names)
    if (!n.empty()) given.push_back(n);
  std::string text;
  for (std::size_t i = 0; i < given.size(); ++i)
    text += (i == 0 ? "" : i + 1 == given.size() ? " or " : ", ") + given[i];
  return text;
}

// The refusals that need no session read: what a mode cannot write, and what it needs of the
// configuration. `option`: how the door names the saved session's option.
void refuseWhatTheModeCannotDo(const RunRequest& request, const Config& config,
                               const OptionNames& names, const std::string& option) {
  const bool localise = !request.localise.empty();
  if (localise && (request.mesh || request.grid || request.octomap))
    throw InputError(option + ": nothing is mapped while localising (no " +
                     oneOf({names.mesh, names.grid, names.octomap}) + ")");
  if (!localise && request.octomap)
    throw InputError(option + ": a session keeps no free space to go on from (no " + names.octomap +
                     ")");
  if (!tracksKeyframes(config.pose, config.tracking))
    throw InputError(option + ": needs the camera's odometry (" + names.key("pose.source") + "=" +
                     config.pose.source + ", " + names.key("tracking.method") + "=" +
                     config.tracking.method + "); use " + names.set("pose.source", "odometry"));
  if (!localise && !config.loop.enabled)
    throw InputError(option +
                     ": goes on from the saved map with loop closure (its places and graph); " +
                     names.key("loop.enabled") + "=false turns it off");
}

// The saved session at `path`, read whole after checking that the run's own files, named after
// `map_path`, would not land beside the saved map's (which stays as it was). Localising keeps
// only the graph and the places (the kept keyframes' images are for fusion).
std::shared_ptr<const Session> openSaved(const std::string& path, const std::string& map_path,
                                         const OptionNames& names, const std::string& option,
                                         bool localise) {
  namespace fs = std::filesystem;
  std::string saved = path;
  while (saved.size() > 1 && saved.back() == '/') saved.pop_back();
  std::error_code ec;
  if (fs::weakly_canonical(sessionPathOf(map_path), ec) == fs::weakly_canonical(saved, ec))
    throw InputError(option + ": the run's files (" + map_path +
                     ") would be written beside the saved map's; give " + names.out +
                     " its own name (e.g. " +
                     (localise ? "localised.pcd: its trajectory is localised_trajectory.txt)"
                               : "continued.pcd: the saved map stays as it was)"));
  Session read = readSession(path);
  if (localise) read.keyframes = {};
  auto session = std::make_shared<const Session>(std::move(read));
  std::size_t places = 0;
  for (const auto& place : session->graph.places) places += place ? 1 : 0;
  spdlog::info("{} {}: {} keyframes, {} places{} (made by {})",
               localise ? "localising in" : "continuing", path, session->graph.keyframes.size(),
               places,
               localise ? "" : fmt::format(", {} kept keyframes", session->keyframes.size()),
               session->created_by);
  return session;
}

}  // namespace

std::shared_ptr<const RunMode> chooseRunMode(const RunRequest& request, Config& config,
                                             const OptionNames& names) {
  const bool localise = !request.localise.empty();
  if (!localise && request.continue_from.empty()) return std::make_shared<MapFromNothing>();
  const std::string& option = localise ? names.localise : names.continue_from;
  // Localising and continuing need the camera's own motion (between placements, before one).
  if (config.pose.source == "auto") config.pose.source = "odometry";
  refuseWhatTheModeCannotDo(request, config, names, option);
  if (localise)
    return std::make_shared<LocaliseInSession>(
        openSaved(request.localise, request.out, names, option, true), request.localise);
  return std::make_shared<ContinueSession>(
      openSaved(request.continue_from, request.out, names, option, false), request.continue_from);
}

}  // namespace rgbdmap
