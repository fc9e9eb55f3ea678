#pragma once

#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "rgbdmap/mapping/map_cloud.hpp"
#include "rgbdmap/runtime/config.hpp"
#include "rgbdmap/runtime/session_merge.hpp"
#include "rgbdmap/runtime/session_stream.hpp"

namespace rgbdmap {

// One map of several robots (rgbdmap_merger): each robot's streamed session is built back
// (SessionAssembler), and merge() places the robots in the first one's frame by the places they
// share (SessionMerger: PlaceMatcher, agreement, one pose graph). A robot that restarts streams a
// new run: the run before stays as a part of its own (its map is not lost), and the new one is
// placed again. The maps are the robots' own clouds, moved by their placements and averaged in
// voxels where they overlap. Safe to call from several threads.
class FleetMerger {
 public:
  struct Robot {
    std::string name;
    bool placed = false;
    Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  // its map frame, merged
    std::string linked_to;  // the robot most of its agreeing places belong to
    int links = 0;
    std::size_t keyframes = 0, places = 0, runs = 0;
  };

  FleetMerger(std::vector<std::string> robots, const Config& settings);

  // One record of robot `index`'s stream (`source`: the topic). kGap: records are missing, ask
  // the robot to send again. Throws InputError naming `source` for a record that is not one.
  SessionAssembler::Result receive(std::size_t index, const std::string& record,
                                   const std::string& source);
  // Robot `index`'s newest map (in its own map frame), made at `stamp` (the time of its newest
  // frame: it belongs to the run that was mapping then).
  void receiveMap(std::size_t index, std::shared_ptr<const MapCloud> map, double stamp);
  // Places the robots with what has arrived, when anything has since the last call (false:
  // nothing new). Runs SessionMerger without holding the lock.
  bool merge();
  std::vector<Robot> robots() const;
  // The merged graph and places of every placed run (no kept keyframes: robots send no images).
  Session session() const;
  // The placed robots' maps in the merged frame, averaged in `voxel` cubes.
  MapCloud map(double voxel) const;

 private:
  struct Part {  // one run of one robot
    std::size_t robot = 0;
    std::uint64_t run = 0;
    SessionAssembler stream;
    bool placed = false;
    SessionMerger::Placement placement;
    std::shared_ptr<const MapCloud> map;  // its newest
  };

  Config settings_;
  std::mutex merging_;  // one merge at a time (the loop's and a save's), the newest written last
  mutable std::mutex mutex_;
  std::vector<Robot> robots_;
  std::vector<std::unique_ptr<Part>> parts_;  // in arrival order; the first robot's first first
  bool changed_ = false;
  Session merged_;
};

}  // namespace rgbdmap
