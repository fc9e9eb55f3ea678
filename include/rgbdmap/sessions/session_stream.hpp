#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rgbdmap/base/binary_record.hpp"
#include "rgbdmap/mapping/keyframe_store.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/slam/loop_closer.hpp"

namespace rgbdmap {

// A session sent live, as it grows: what a robot gives a fleet's merger (docs/ros.md). Records
// of the session's own encoding (binary_record: kind, version, checksum), one a message:
//  - a graph record: the run's id, the camera, the keyframes added since the last graph record
//    (timestamp, odometry, pose as optimised when sent) and the edges added since;
//  - a place record: one keyframe's place (ORB features with 3-D points, and the dense reference
//    packed as loop closure keeps it: 8 bytes a point);
//  - a piece record: one keyframe of the map at half resolution (map_piece.hpp) with its
//    odometry pose and anchor, to be fused by the merger at the poses of its graph.
// Graph records always go (a few hundred bytes a keyframe); places (about 150 KB each: the
// reference is most of it) and then pieces (about 16 KB) wait for the byte budget, oldest first.
// Pieces waiting are kept within `piece_memory` (beyond it the most redundant view is let go, as
// KeyframeStore does), and so are those sent, to send again to a merger that asks.
class SessionStream {
 public:
  struct Options {
    double bytes_per_second = 750e3;  // the average the records stay under
    double burst_seconds = 2.0;       // budget saved while idle, at most
    double piece_memory = 32e6;       // bytes of pieces kept (to send, and to send again)
    // A keyframe becomes a piece this far from the last piece's viewpoint (viewpointDistance:
    // metres, a turn counting 2 m per radian).
    double piece_spacing = 0.1;
  };
  struct Record {
    enum class Kind { kGraph, kPlace, kPiece } kind;
    std::string bytes;
  };
  struct Totals {
    std::uint64_t keyframes = 0, edges = 0, places = 0, pieces = 0, bytes = 0, restarts = 0;
    std::uint64_t piece_bytes = 0;
  };

  // `run`: this run's id (a robot that restarts is a new run: its old part is not duplicated).
  SessionStream(std::uint64_t run, const CameraIntrinsics& camera, Options options);

  // The records due at `now` (steady-clock seconds): what the graph gained since the last call,
  // then places while the budget allows. Reads the graph under its lock once (loop closure
  // waits at most that long).
  std::vector<Record> take(const LoopCloser& graph, double now);
  // A keyframe the map took (its pose the odometry's): made a piece (makeMapPiece) when its
  // viewpoint is `piece_spacing` from the last piece's, sent once the graph record with its
  // anchor went.
  void addKeyframe(const Frame& keyframe);
  // Everything again from the first keyframe (a merger that started late, or lost records).
  void restart();
  const Totals& totals() const { return totals_; }
  std::uint64_t run() const { return run_; }

 private:
  std::uint64_t run_;
  CameraIntrinsics camera_;
  Options options_;
  std::size_t keyframes_sent_ = 0, edges_sent_ = 0, next_place_ = 0;
  KeyframeStore pieces_;
  std::optional<Eigen::Isometry3d> last_piece_;  // where the last piece was seen from
  Frame piece_;                                  // buffers
  std::uint64_t next_piece_ = 0;                 // frame index: pieces from it on are still to send
  double budget_ = 0.0;                          // bytes; may go below zero by one place
  double budget_at_ = -1.0;
  Totals totals_;
};

// The run a session record comes from (none: not a session record). Not checked beyond that:
// SessionAssembler::apply() checks the whole record.
std::optional<std::uint64_t> runOfRecord(const std::string& record);

// Builds a session back from its stream (a merger's view of one robot).
class SessionAssembler {
 public:
  enum class Result {
    kApplied,
    kNewRun,  // the record came from another run: what was assembled was dropped first
    kGap,     // records are missing before it: not applied (ask for the stream again)
  };
  // Throws InputError naming `source` (a topic) when `record` is not a session record or is
  // damaged; what was assembled stays.
  Result apply(const std::string& record, const std::string& source);

  std::uint64_t run() const { return run_; }
  std::size_t keyframes() const { return session_.graph.keyframes.size(); }
  std::size_t edges() const { return session_.graph.edges.size(); }
  std::size_t places() const { return places_.size(); }
  std::size_t pieces() const { return pieces_.size(); }
  const CameraIntrinsics& camera() const { return session_.camera; }
  // The pieces so far, oldest first: images as sent, `pose` the odometry's, `anchor` the
  // keyframe (of this run's graph) whose correction moves it.
  std::vector<KeyframeStore::Entry> mapPieces() const;
  // What was assembled, as the records that would assemble it again (a merger saving what it
  // has, to pick up from), with `more_pieces` (let go here, kept elsewhere) among its pieces.
  std::vector<std::string> records(const std::vector<KeyframeStore::Entry>& more_pieces) const;
  // Lets a piece go once it is kept elsewhere (the merger's map).
  void forgetMapPiece(std::uint64_t index) { pieces_.erase(index); }
  // The session so far: camera, keyframes, edges and places (no kept keyframes: no images).
  Session session() const;

 private:
  void reset(std::uint64_t run);
  Result applyGraph(BinaryReader& in);
  Result applyPlace(BinaryReader& in);
  Result applyPiece(BinaryReader& in);

  std::uint64_t run_ = 0;
  bool started_ = false;
  Session session_;
  std::map<std::size_t, std::shared_ptr<const PlaceRecognition::Place>> places_;
  std::map<std::uint64_t, KeyframeStore::Entry> pieces_;  // by frame index
};

}  // namespace rgbdmap
