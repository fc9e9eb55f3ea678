#include "rgbdmap/runtime/fleet_merger.hpp"

#include <spdlog/spdlog.h>

#include <unordered_map>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {

FleetMerger::FleetMerger(std::vector<std::string> robots, const Config& settings)
    : settings_(settings) {
  for (std::string& name : robots) {
    Robot robot;
    robot.name = std::move(name);
    robots_.push_back(std::move(robot));
  }
}

SessionAssembler::Result FleetMerger::receive(std::size_t index, const std::string& record,
                                              const std::string& source) {
  const std::optional<std::uint64_t> run = runOfRecord(record);
  // Not a session record: the assembler's check says what it is instead (it throws).
  if (!run) return SessionAssembler().apply(record, source);
  std::lock_guard<std::mutex> lock(mutex_);
  Part* part = nullptr;
  for (auto& p : parts_)
    if (p->robot == index && p->run == *run) part = p.get();
  if (!part) {
    // A robot's new run: the runs before stay (their maps are not lost).
    parts_.push_back(std::make_unique<Part>());
    part = parts_.back().get();
    part->robot = index;
    part->run = *run;
    if (++robots_.at(index).runs > 1)
      spdlog::info("merger: {} restarted (run {}): its new run is placed again, the old one stays",
                   robots_[index].name, *run);
  }
  const SessionAssembler::Result result = part->stream.apply(record, source);
  changed_ = changed_ || result != SessionAssembler::Result::kGap;
  return result;
}

void FleetMerger::receiveMap(std::size_t index, std::shared_ptr<const MapCloud> map, double stamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  Part* target = nullptr;
  for (auto& p : parts_) {
    if (p->robot != index) continue;
    const Session s = p->stream.session();
    // The run whose keyframes began before the map was made (the newest such).
    if (!target || s.graph.keyframes.empty() || s.graph.keyframes.front().timestamp <= stamp)
      target = p.get();
  }
  if (!target) return;  // no stream from it yet: the map has no place
  target->map = std::move(map);
  changed_ = true;
}

bool FleetMerger::merge() {
  const std::lock_guard<std::mutex> one_at_a_time(merging_);
  // The parts to merge, the first robot's first run first (its frame is the merged one).
  std::vector<Part*> order;
  std::vector<Session> sessions;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!changed_) return false;
    changed_ = false;
    for (std::size_t robot = 0; robot < robots_.size(); ++robot)
      for (auto& p : parts_)
        if (p->robot == robot && p->stream.keyframes() > 0) order.push_back(p.get());
    if (order.empty() || order.front()->robot != 0) return false;  // the first robot first
    for (Part* p : order) sessions.push_back(p->stream.session());
  }
  std::vector<SessionMerger::Placement> placements;
  Session merged = SessionMerger(settings_).merge(sessions, placements);
  merged.configuration = settings_.toYaml();
  merged.created_by = "rgbdmap merger";

  std::lock_guard<std::mutex> lock(mutex_);
  merged_ = std::move(merged);
  for (std::size_t i = 0; i < order.size(); ++i) {
    order[i]->placed = placements[i].placed;
    order[i]->placement = placements[i];
  }
  for (std::size_t robot = 0; robot < robots_.size(); ++robot) {
    Robot& r = robots_[robot];
    // A robot is where its newest run is (its TF frame is that run's).
    const Part* newest = nullptr;
    std::size_t keyframes = 0, places = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (order[i]->robot != robot) continue;
      newest = order[i];
      keyframes += order[i]->stream.keyframes();
      places += order[i]->stream.places();
    }
    r.keyframes = keyframes;
    r.places = places;
    const bool was_placed = r.placed;
    r.placed = newest && newest->placed;
    if (!r.placed) continue;
    r.transform = newest->placement.transform;
    r.links = newest->placement.links;
    const int linked = newest->placement.linked_to;
    r.linked_to = linked >= 0 ? robots_[order[static_cast<std::size_t>(linked)]->robot].name : "";
    if (!was_placed && robot > 0)
      spdlog::info("merger: {} placed, linked with {} by {} places", r.name, r.linked_to, r.links);
  }
  return true;
}

std::vector<FleetMerger::Robot> FleetMerger::robots() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return robots_;
}

Session FleetMerger::session() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return merged_;
}

MapCloud FleetMerger::map(double voxel) const {
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Vector3d colour = Eigen::Vector3d::Zero();
    int count = 0;
  };
  std::unordered_map<std::int64_t, Cell> cells;
  const auto key = [voxel](const Eigen::Vector3d& p) {
    const Eigen::Vector3i c = (p / voxel).array().floor().cast<int>();
    return (static_cast<std::int64_t>(c.x() & 0x1fffff) << 42) |
           (static_cast<std::int64_t>(c.y() & 0x1fffff) << 21) | (c.z() & 0x1fffff);
  };
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& part : parts_) {
      if (!part->placed || !part->map) continue;
      const Eigen::Isometry3d& t = part->placement.transform;
      for (const pcl::PointXYZRGB& q : part->map->points) {
        const Eigen::Vector3d p = t * Eigen::Vector3d(q.x, q.y, q.z);
        Cell& c = cells[key(p)];
        c.sum += p;
        c.colour += Eigen::Vector3d(q.r, q.g, q.b);
        ++c.count;
      }
    }
  }
  MapCloud cloud;
  cloud.reserve(cells.size());
  for (const auto& [k, c] : cells) {
    pcl::PointXYZRGB p;
    const Eigen::Vector3d mean = c.sum / c.count;
    const Eigen::Vector3d colour = c.colour / c.count;
    p.x = static_cast<float>(mean.x());
    p.y = static_cast<float>(mean.y());
    p.z = static_cast<float>(mean.z());
    p.r = static_cast<std::uint8_t>(colour.x() + 0.5);
    p.g = static_cast<std::uint8_t>(colour.y() + 0.5);
    p.b = static_cast<std::uint8_t>(colour.z() + 0.5);
    cloud.push_back(p);
  }
  return cloud;
}

}  // namespace rgbdmap
