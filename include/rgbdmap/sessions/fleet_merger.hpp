#pragma once

#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/mapping/mapper.hpp"
#include "rgbdmap/sessions/session_merge.hpp"
#include "rgbdmap/sessions/session_stream.hpp"
#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {

// One map of several robots (rgbdmap_merger): each robot's streamed session is built back
// (SessionAssembler), and merge() places the robots in the first one's frame by the places they
// share (SessionMerger: PlaceMatcher, agreement, one pose graph). A robot that restarts streams a
// new run: the run before stays as a part of its own (its map is not lost), and the new one is
// placed again. The map is fused from the placed runs' map pieces (map_piece.hpp) into one TSDF
// at the merged graph's poses, and follows that graph as a robot's map follows its own (Mapper:
// pieces a merge moves are fused again): where two robots saw one wall, one surface. Safe to
// call from several threads.
class FleetMerger {
 public:
  struct Robot {
    std::string name;
    bool placed = false;
    Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  // its map frame, merged
    std::string linked_to;  // the robot most of its agreeing places belong to
    int links = 0;
    std::size_t keyframes = 0, places = 0, pieces = 0, runs = 0;  // pieces: received
    std::size_t compared = 0;  // its place pairs compared so far (SessionMerger::Placement)
  };
  // What the merger has done so far: merges and the CPU time they took (one thread's), maps.
  struct Work {
    std::size_t merges = 0, maps = 0;
    double merge_seconds = 0.0;
  };

  // `settings`: the configuration of the merge (loop.*) and of the merged map (filter.*, map.*,
  // loop.refusion_*).
  FleetMerger(std::vector<std::string> robots, const Config& settings);

  // One record of robot `index`'s stream (`source`: the topic). kGap: records are missing, ask
  // the robot to send again. Throws InputError naming `source` for a record that is not one.
  SessionAssembler::Result receive(std::size_t index, const std::string& record,
                                   const std::string& source);
  // Places the robots with what has arrived, when anything has since the last call (false:
  // nothing new). Runs SessionMerger without holding the lock.
  bool merge();
  std::vector<Robot> robots() const;
  Work work() const;
  // The merged graph and places of every placed run (no kept keyframes: the pieces are at a
  // quarter of the resolution, not what a run continued from the session would fuse), and every
  // run's stream as received (Session::streams, its pieces as the map keeps them).
  Session session();
  // Picks up from a saved merged session: its robots' streams taken in again, as if they had
  // just arrived (those of robots not in the list are left out, and said). Returns the runs
  // taken. A robot that then sends its session again adds nothing twice.
  std::size_t resume(const Session& saved, const std::string& source);
  // The merged map: the placed runs' pieces that have not been fused yet are, and the map is
  // brought to the latest merge's poses. Robots with another camera than the first placed one's
  // are fused into TSDFs of their own (their clouds are written together).
  MapCloud map();

 private:
  struct Part {  // one run of one robot
    std::size_t robot = 0;
    std::uint64_t run = 0;
    SessionAssembler stream;
    bool placed = false;
    SessionMerger::Placement placement;
    std::vector<std::int64_t> slots;  // each graph keyframe's id in corrections_
    // The poses in the merged graph of the keyframes the latest merge placed (their corrections
    // are known; none when it was not placed): the next merge looks for new places near there.
    SessionMerger::PlacedBefore merged_poses;
    std::set<std::uint64_t> fused;  // the frame indices of its pieces fused so far
    double last_record_at = 0.0;    // steady-clock seconds
  };
  struct CameraMap {  // the TSDF of the pieces of one camera
    CameraIntrinsics camera;
    std::unique_ptr<Mapper> mapper;
  };

  Config settings_;
  std::mutex merging_;  // one merge at a time (the loop's and a save's), the newest written last
  SessionMerger::PlaceComparisons comparisons_;  // of all merges so far (under merging_)
  mutable std::mutex mutex_;
  std::vector<Robot> robots_;
  Work work_;
  std::vector<std::unique_ptr<Part>> parts_;  // in arrival order; the first robot's first first
  bool changed_ = false;
  Session merged_;
  std::int64_t slots_ = 0;  // keyframes received, over all parts
  // Each slot's part (index in parts_) and keyframe in it.
  std::vector<std::pair<std::size_t, std::size_t>> slot_owner_;
  PoseCorrections corrections_;  // by slot: the merged graph's correction of each keyframe

  std::mutex mapping_;  // one map() at a time: the mappers are not shared
  RunStats stats_;
  std::vector<CameraMap> maps_;
};

}  // namespace rgbdmap
