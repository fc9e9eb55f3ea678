#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/map_files/trajectory_stream.hpp"
#include "rgbdmap/mapping/keyframe_store.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/slam/loop_closer.hpp"

namespace rgbdmap {

// A mapping session, saved beside its map (MAP.session/, docs/sessions.md) with every checkpoint
// and at the end: what a later run needs to go on from it. The places and the pose graph come
// from loop closure, the map as the kept keyframes' compressed images (the map is fused from
// them again at their poses), with the camera and the effective configuration.
struct Session {
  static constexpr std::uint32_t kFormatVersion = 1;

  std::string created_by;  // "rgbdmap <version>"
  CameraIntrinsics camera;
  std::string configuration;  // the effective configuration, YAML
  LoopCloser::Saved graph;
  // Set while a run writes its session: the graph and places are then read from the loop closer
  // as they are when written (streamed under its lock, not copied) and `graph` is not used.
  const LoopCloser* live_graph = nullptr;
  std::vector<KeyframeStore::Entry> keyframes;  // the kept ones, images shared
  // The trajectories of the runs behind it, as their spools hold them (TrajectoryStream): each
  // pose as tracked with its anchor keyframe, so the graph corrects it. Every frame tracked and
  // every keyframe fused; a run that continues the session writes them before its own, so that
  // its trajectory files hold every run's poses, at the one graph's final poses.
  std::vector<AnchoredPose> frames, fused;
  // Set while a run writes its session: its spools, copied into the session as they are (not
  // held in memory: an hour's frames are 10 MB); "" = `frames` and `fused` are written.
  std::string frames_spool, fused_spool;
  // A fleet's merged session (rgbdmap_merger): each robot run's session stream as the merger
  // had it (SessionStream records: graph, places, map pieces), so that a merger restarted from
  // the session picks up again (streams.bin; none in a run's own session).
  struct Stream {
    std::string robot;
    std::vector<std::string> records;
  };
  std::vector<Stream> streams;
};

// What a session folder holds, read from it (`rgbdmap session`, the log).
struct SessionSummary {
  std::size_t keyframes = 0, edges = 0, loop_edges = 0, places = 0, kept_keyframes = 0;
  std::uint64_t bytes = 0;  // all files
};

// What the sessions one run writes only ever add to, as far as the writer knows it: the kept
// keyframes' images (images.bin) and the places (places.data), which never change once made. So
// each session after the first links those files of the one before and appends only what is new
// since: the earlier session's keyframes.bin and places.bin name only bytes before that, so it
// stays whole until the new folder takes its place. When images.bin holds more images let go
// than kept, it is written anew.
struct SessionAppends {
  struct File {
    std::uint64_t inode = 0;  // of the file in the session last written
    std::uint64_t bytes = 0;  // of it, as that session's index knows it
  };
  struct ImagesAt {
    std::uint64_t offset = 0, depth_bytes = 0, colour_bytes = 0;
  };
  struct PlaceAt {
    std::uint64_t offset = 0, bytes = 0;  // bytes 0: no place
  };
  std::string session;  // the folder last written ("" = none yet)
  File images, places;
  std::unordered_map<std::uint64_t, ImagesAt> images_by_id;  // by KeyframeStore::Entry::id
  // By graph keyframe id, with the place they were written from (a place replaced is new).
  std::unordered_map<std::uint64_t, std::pair<PlaceAt, const void*>> places_by_id;
  std::uint64_t appended = 0;  // by the last write: images and places new to the files
};

// Writes `session` as folder `path`: the files go into a new folder beside it, which then takes
// the old one's place in one step (so `path` is always a whole session, the old or the new).
// Returns false with `error` naming the path and the system error; the old session stays.
// `appends` (null: every file written whole): what the last session this run wrote there holds,
// so that only new images and places are written; updated when the write succeeds.
bool writeSession(const Session& session, const std::string& path, std::string& error,
                  std::uint64_t* bytes = nullptr, SessionAppends* appends = nullptr);

// Reads a session folder back. Throws InputError naming the file that is missing, from another
// format version, truncated or corrupt.
Session readSession(const std::string& path);
SessionSummary summarise(const Session& session, const std::string& path);

// The corrections the session's graph makes to its keyframes' odometry (PoseCorrections'
// table: optimised pose times the inverse of the odometry pose, by keyframe id).
PoseCorrections::Table correctionsOf(const Session& session);
// A pose of one of the session's trajectories, anchored to a keyframe its graph holds: one
// tracked before the first keyframe is expressed in that keyframe's frame, one tracked after the
// newest one the graph holds (a checkpoint's session) shares the newest's correction, as it did
// in its run.
AnchoredPose anchoredInGraph(const Session& session, AnchoredPose pose);
// The graph's keyframes at their optimised poses, in time order (`rgbdmap session
// --trajectory`, and what a merge writes beside its map).
Trajectory graphTrajectory(const Session& session);
// One of the session's trajectories (`frames` or `fused`) at the graph's poses, in time order.
Trajectory resolvedTrajectory(const Session& session, const std::vector<AnchoredPose>& poses);

// Fuses the session's kept keyframes into `mapper` at the graph's poses (the mapper made with
// `corrections`, published here): the session's map, as a later run starts from it.
void fuseSession(const Session& session, PoseCorrections& corrections, Mapper& mapper);

}  // namespace rgbdmap
