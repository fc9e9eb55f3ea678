#include "rgbdmap/sessions/fleet_merger.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/steady_time.hpp"
#include "rgbdmap/sessions/map_piece.hpp"

namespace rgbdmap {

FleetMerger::FleetMerger(std::vector<std::string> robots, const Config& settings)
    : settings_(settings) {
  // The filter's windows are in pixels, a piece's pixel is 4 of the camera's: neighbours are 4
  // times further apart (a slanted surface jumps 4 times more between them), and a block's
  // average has smoothed already. (Unscaled: recall 0.93 instead of 0.99 on a synthetic lap.)
  settings_.filter.edge_jump *= kMapPieceStep;
  settings_.filter.smooth_radius = settings_.filter.smooth_radius / kMapPieceStep;
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
  std::size_t part_index = 0;
  for (std::size_t i = 0; i < parts_.size(); ++i)
    if (parts_[i]->robot == index && parts_[i]->run == *run) {
      part = parts_[i].get();
      part_index = i;
    }
  if (!part) {
    // A robot's new run: the runs before stay (their maps are not lost).
    parts_.push_back(std::make_unique<Part>());
    part = parts_.back().get();
    part_index = parts_.size() - 1;
    part->robot = index;
    part->run = *run;
    if (++robots_.at(index).runs > 1)
      spdlog::info("merger: {} restarted (run {}): its new run is placed again, the old one stays",
                   robots_[index].name, *run);
  }
  const SessionAssembler::Result result = part->stream.apply(record, source);
  part->last_record_at = steadySeconds();
  changed_ = changed_ || result != SessionAssembler::Result::kGap;
  // Keyframes are numbered for the merged map's corrections as they arrive, once for good.
  while (part->slots.size() < part->stream.keyframes()) {
    slot_owner_.emplace_back(part_index, part->slots.size());
    part->slots.push_back(slots_++);
  }
  return result;
}

bool FleetMerger::merge() {
  const std::lock_guard<std::mutex> one_at_a_time(merging_);
  const double started = threadCpuSeconds();
  // The parts to merge, the first robot's first run first (its frame is the merged one).
  std::vector<Part*> order;
  std::vector<Session> sessions;
  std::vector<SessionMerger::PlacedBefore> placed_before;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!changed_) return false;
    changed_ = false;
    for (std::size_t robot = 0; robot < robots_.size(); ++robot)
      for (auto& p : parts_)
        if (p->robot == robot && p->stream.keyframes() > 0) order.push_back(p.get());
    if (order.empty() || order.front()->robot != 0) return false;  // the first robot first
    for (Part* p : order) {
      sessions.push_back(p->stream.session());
      placed_before.push_back(p->merged_poses);
    }
  }
  std::vector<SessionMerger::Placement> placements;
  Session merged =
      SessionMerger(settings_).merge(sessions, placements, &comparisons_, placed_before);
  merged.configuration = settings_.toYaml();
  merged.created_by = "rgbdmap merger";

  std::lock_guard<std::mutex> lock(mutex_);
  // Each placed keyframe's correction (merged pose times its odometry's inverse), by slot.
  // A run this merge did not place (it was before) keeps where it was.
  const std::shared_ptr<const PoseCorrections::Table> before = corrections_.snapshot().table;
  PoseCorrections::Table table = before ? *before : PoseCorrections::Table{};
  table.resize(static_cast<std::size_t>(slots_), Eigen::Isometry3d::Identity());
  for (std::size_t i = 0; i < order.size(); ++i) {
    order[i]->placed = placements[i].placed;
    order[i]->placement = placements[i];
    order[i]->merged_poses.clear();
    if (!placements[i].placed) continue;
    for (std::size_t k = 0; k < sessions[i].graph.keyframes.size(); ++k) {
      const auto& node = merged.graph.keyframes[placements[i].first_keyframe + k];
      table[static_cast<std::size_t>(order[i]->slots[k])] = node.pose * node.odometry.inverse();
      order[i]->merged_poses.push_back(node.pose);
    }
  }
  corrections_.publish(std::move(table));
  merged_ = std::move(merged);
  ++work_.merges;
  work_.merge_seconds += threadCpuSeconds() - started;
  for (std::size_t robot = 0; robot < robots_.size(); ++robot) {
    Robot& r = robots_[robot];
    // A robot is where its newest run is (its TF frame is that run's).
    const Part* newest = nullptr;
    std::size_t keyframes = 0, places = 0, pieces = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (order[i]->robot != robot) continue;
      newest = order[i];
      keyframes += order[i]->stream.keyframes();
      places += order[i]->stream.places();
      pieces += order[i]->stream.pieces() + order[i]->fused.size();
    }
    r.keyframes = keyframes;
    r.places = places;
    r.pieces = pieces;
    for (std::size_t i = 0; i < order.size(); ++i)
      if (order[i]->robot == robot) r.compared += placements[i].compared;
    const bool was_placed = r.placed;
    r.placed = newest && newest->placed;
    if (!r.placed) continue;
    r.transform = newest->placement.transform;
    r.links = newest->placement.links;
    const int linked = newest->placement.linked_to;
    r.linked_to = linked >= 0 ? robots_[order[static_cast<std::size_t>(linked)]->robot].name : "";
    if (!was_placed && robot > 0)
      spdlog::info(
          "merger: {} placed, linked with {} by {} places ({:.2f} s after its newest "
          "record arrived)",
          r.name, r.linked_to, r.links, steadySeconds() - newest->last_record_at);
  }
  return true;
}

std::vector<FleetMerger::Robot> FleetMerger::robots() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return robots_;
}

FleetMerger::Work FleetMerger::work() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return work_;
}

Session FleetMerger::session() {
  const std::lock_guard<std::mutex> mapping(mapping_);  // (map()'s order: mapping_, mutex_)
  std::lock_guard<std::mutex> lock(mutex_);
  Session saved = merged_;
  // The pieces the maps keep (fused: let go by the streams), back to their runs.
  std::vector<std::vector<KeyframeStore::Entry>> fused(parts_.size());
  for (const CameraMap& m : maps_)
    for (KeyframeStore::Entry piece : m.mapper->keptKeyframes().entries()) {
      const auto& [part, node] = slot_owner_.at(static_cast<std::size_t>(piece.anchor));
      piece.anchor = static_cast<std::int64_t>(node);
      fused[part].push_back(std::move(piece));
    }
  for (std::size_t i = 0; i < parts_.size(); ++i)
    saved.streams.push_back({robots_[parts_[i]->robot].name, parts_[i]->stream.records(fused[i])});
  return saved;
}

std::size_t FleetMerger::resume(const Session& saved, const std::string& source) {
  std::size_t runs = 0;
  for (const Session::Stream& stream : saved.streams) {
    std::size_t robot = 0;
    while (robot < robots_.size() && robots_[robot].name != stream.robot) ++robot;
    if (robot == robots_.size()) {
      spdlog::info("merger: {}: {} is not among the robots: its run is left out", source,
                   stream.robot);
      continue;
    }
    for (const std::string& record : stream.records) receive(robot, record, source);
    ++runs;
  }
  return runs;
}

MapCloud FleetMerger::map() {
  const std::lock_guard<std::mutex> one_at_a_time(mapping_);
  struct Due {
    const std::string* robot;
    CameraIntrinsics camera;
    KeyframeStore::Entry piece;
  };
  std::vector<Due> due;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& part : parts_) {
      if (!part->placed) continue;
      const CameraIntrinsics camera = mapPieceCamera(part->stream.camera());
      for (KeyframeStore::Entry& piece : part->stream.mapPieces()) {
        // Anchored to a keyframe whose correction is known (-1: tracked from the first
        // keyframe, which its robot's graph holds still: the first's correction moves it).
        const std::int64_t node = std::max<std::int64_t>(piece.anchor, 0);
        if (node >= static_cast<std::int64_t>(part->merged_poses.size())) continue;
        // The mapper keeps it from now on (a piece sent again is not fused twice).
        part->stream.forgetMapPiece(piece.index);
        if (!part->fused.insert(piece.index).second) continue;
        piece.anchor = part->slots[static_cast<std::size_t>(node)];
        due.push_back({&robots_[part->robot].name, camera, std::move(piece)});
      }
    }
  }
  KeyframeStore decoder(0);
  Frame frame;
  for (const Due& d : due) {
    auto same = [&](const CameraMap& m) {
      const CameraIntrinsics& c = m.camera;
      return c.width == d.camera.width && c.height == d.camera.height && c.fx == d.camera.fx &&
             c.fy == d.camera.fy && c.cx == d.camera.cx && c.cy == d.camera.cy &&
             c.distortion() == d.camera.distortion();
    };
    auto it = std::find_if(maps_.begin(), maps_.end(), same);
    if (it == maps_.end()) {
      maps_.push_back(
          {d.camera, std::make_unique<Mapper>(d.camera, settings_.filter, settings_.map,
                                              settings_.refusion, stats_, &corrections_)});
      it = std::prev(maps_.end());
    }
    try {
      decoder.decode(d.piece, frame);
    } catch (const std::exception& e) {
      spdlog::warn("merger: {}'s map piece of frame {} left out: {}", *d.robot, d.piece.index,
                   e.what());
      continue;
    }
    it->mapper->fuse(frame);
  }
  MapCloud cloud;
  for (CameraMap& m : maps_) {
    m.mapper->settle();
    cloud += *m.mapper->snapshot();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  ++work_.maps;
  return cloud;
}

}  // namespace rgbdmap
