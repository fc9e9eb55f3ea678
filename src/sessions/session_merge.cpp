#include "rgbdmap/sessions/session_merge.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <map>

#include "rgbdmap/mapping/keyframe_store.hpp"
#include "rgbdmap/slam/motion.hpp"
#include "rgbdmap/slam/place_matcher.hpp"
#include "rgbdmap/slam/place_recognition.hpp"
#include "rgbdmap/slam/pose_graph.hpp"

namespace rgbdmap {
namespace {

// A kept keyframe's graph keyframe: its anchor, or the nearest one the graph has (a keyframe
// fused before the loop closer took its anchor in shares the newest correction; one with no
// anchor was fused as tracked, which is keyframe 0's frame).
int nodeOf(const KeyframeStore::Entry& entry, std::size_t keyframes) {
  if (entry.anchor < 0 || keyframes == 0) return 0;
  return static_cast<int>(
      std::min<std::int64_t>(entry.anchor, static_cast<std::int64_t>(keyframes) - 1));
}

}  // namespace

struct SessionMerger::Match {
  int target = 0;  // the merged keyframe whose place it was found at
  int node = 0;    // the session's keyframe the kept keyframe is anchored to
  Eigen::Isometry3d measurement = Eigen::Isometry3d::Identity();  // X_target^-1 * X_node
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  // the session's frame, merged
  int inliers = 0;
};

SessionMerger::SessionMerger(const Config& settings, Options options)
    : settings_(settings), options_(options) {}

SessionMerger::PlaceComparisons::Result& SessionMerger::PlaceComparisons::of(
    const std::shared_ptr<const PlaceRecognition::Place>& target,
    const std::shared_ptr<const PlaceRecognition::Place>& query, bool& known) {
  const auto key = std::make_pair(target.get(), query.get());
  const auto found = results_.find(key);
  known = found != results_.end();
  if (known) return found->second;
  held_.insert(target);
  held_.insert(query);
  return results_[key];
}

std::vector<SessionMerger::Match> SessionMerger::findMatches(const Session& merged,
                                                             const Session& session,
                                                             PlaceComparisons* comparisons,
                                                             const PlacedBefore& before,
                                                             std::size_t& compared) const {
  if (session.keyframes.empty())
    return findPlaceMatches(merged, session, comparisons, before, compared);
  PlaceRecognition recognition(session.camera, settings_.tracking, settings_.loop,
                               settings_.filter.min_depth, settings_.filter.max_depth);
  std::vector<int> candidates;
  for (std::size_t id = 0; id < merged.graph.places.size(); ++id) {
    if (!merged.graph.places[id]) continue;
    recognition.restore(static_cast<int>(id), merged.graph.places[id]);
    candidates.push_back(static_cast<int>(id));
  }
  std::vector<Match> matches;
  if (candidates.empty() || session.graph.keyframes.empty()) return matches;
  const auto slot = static_cast<std::uint64_t>(merged.graph.keyframes.size());
  const PoseCorrections::Table corrections = correctionsOf(session);
  const std::size_t stride = std::max<std::size_t>(
      1, session.keyframes.size() / std::max<std::size_t>(1, options_.max_queries));
  KeyframeStore decoder(0);
  Frame frame;
  for (std::size_t i = 0; i < session.keyframes.size(); i += stride) {
    const KeyframeStore::Entry& entry = session.keyframes[i];
    decoder.decode(entry, frame);
    TrackedKeyframe query;
    query.id = slot;
    query.timestamp = entry.timestamp;
    query.color = frame.color;
    query.depth = frame.depth;
    recognition.add(query);
    PlaceRecognition::Counts counts;
    const std::optional<LoopMeasurement> found = recognition.find(candidates, counts);
    compared += candidates.size();
    recognition.forget(static_cast<int>(slot));
    if (!found) continue;
    Match m;
    m.node = nodeOf(entry, session.graph.keyframes.size());
    // Where the kept keyframe is in the session's frame, and relative to its graph keyframe.
    const Eigen::Isometry3d in_session =
        entry.anchor < 0 ? entry.pose : corrections[static_cast<std::size_t>(m.node)] * entry.pose;
    const Eigen::Isometry3d in_node =
        session.graph.keyframes[static_cast<std::size_t>(m.node)].pose.inverse() * in_session;
    m.target = found->earlier;
    m.transform = frameInSavedMap(merged.graph.keyframes[static_cast<std::size_t>(m.target)].pose,
                                  found->later_in_earlier, in_session);
    m.measurement = found->later_in_earlier * in_node.inverse();
    m.information = found->information;
    m.inliers = found->inliers;
    matches.push_back(m);
  }
  return matches;
}

std::vector<std::vector<int>> SessionMerger::nearPlaces(const Session& merged,
                                                        const Session& session,
                                                        const PlacedBefore& before) const {
  const auto& own = session.graph.keyframes;
  const LoopOptions& o = settings_.loop;
  std::vector<std::vector<int>> near(own.size());
  if (before.empty()) return near;
  double walked = 0.0;  // since the last keyframe placed before
  for (std::size_t k = 0; k < own.size(); ++k) {
    // A keyframe placed before is where it was put; a newer one follows the last placed by its
    // own odometry, and may have drifted since by what its path allows.
    const std::size_t last = std::min(k, before.size() - 1);
    if (k > last) walked += pathLength(own[k - 1].pose.inverse() * own[k].pose);
    if (k >= session.graph.places.size() || !session.graph.places[k]) continue;
    const Eigen::Isometry3d x = before[last] * own[last].pose.inverse() * own[k].pose;
    const double allowance = o.drift_per_metre * walked;
    std::vector<std::pair<double, int>> found;
    for (std::size_t id = 0; id < merged.graph.places.size(); ++id) {
      if (!merged.graph.places[id]) continue;
      if (const auto distance =
              loopSearchDistance(x, merged.graph.keyframes[id].pose, allowance, o))
        found.emplace_back(*distance, static_cast<int>(id));
    }
    std::sort(found.begin(), found.end());
    for (const auto& f : found) near[k].push_back(f.second);
  }
  return near;
}

std::vector<SessionMerger::Match> SessionMerger::findPlaceMatches(const Session& merged,
                                                                  const Session& session,
                                                                  PlaceComparisons* comparisons,
                                                                  const PlacedBefore& before,
                                                                  std::size_t& compared) const {
  PlaceComparisons own;  // none kept: this merge's only
  PlaceComparisons& results = comparisons ? *comparisons : own;
  PlaceMatcher matcher(session.camera, settings_.tracking, settings_.loop);
  std::vector<int> everywhere, queries;
  for (std::size_t id = 0; id < merged.graph.places.size(); ++id)
    if (merged.graph.places[id]) everywhere.push_back(static_cast<int>(id));
  const std::size_t keyframes = session.graph.keyframes.size();
  for (std::size_t id = 0; id < std::min(keyframes, session.graph.places.size()); ++id)
    if (session.graph.places[id]) queries.push_back(static_cast<int>(id));
  const std::vector<std::vector<int>> near = nearPlaces(merged, session, before);
  std::vector<Match> matches;
  // Everywhere, every place against every place would grow with the square of the fleet's
  // ground: a spread of the session's places. Near where it was placed, each place.
  const std::size_t stride =
      before.empty() ? std::max<std::size_t>(
                           1, queries.size() / std::max<std::size_t>(1, options_.max_queries))
                     : 1;
  for (std::size_t i = 0; i < queries.size(); i += stride) {
    const int node = queries[i];
    const auto& query = session.graph.places[static_cast<std::size_t>(node)];
    const std::vector<int>& targets =
        before.empty() ? everywhere : near[static_cast<std::size_t>(node)];
    const auto pair = [&](int target) -> PlaceComparisons::Result& {
      bool known = false;
      PlaceComparisons::Result& r =
          results.of(merged.graph.places[static_cast<std::size_t>(target)], query, known);
      if (!known) {
        r.alike =
            matcher.similarity(*merged.graph.places[static_cast<std::size_t>(target)], *query);
        ++compared;
      }
      return r;
    };
    // The most alike places first, as loop closure ranks its candidates.
    std::vector<std::pair<int, int>> ranked;  // (matches, id)
    for (const int target : targets) {
      const int alike = pair(target).alike;
      if (alike >= settings_.loop.min_matches) ranked.emplace_back(alike, target);
    }
    std::stable_sort(ranked.begin(), ranked.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    if (static_cast<int>(ranked.size()) > settings_.loop.max_candidates)
      ranked.resize(static_cast<std::size_t>(settings_.loop.max_candidates));
    for (const auto& [alike, target] : ranked) {
      PlaceComparisons::Result& result = pair(target);
      if (!result.verified) {
        result.found =
            matcher.match(*merged.graph.places[static_cast<std::size_t>(target)], *query);
        result.verified = true;
      }
      const std::optional<LoopMeasurement>& found = result.found;
      if (!found) continue;
      Match m;
      m.node = node;
      m.target = target;
      m.transform = frameInSavedMap(merged.graph.keyframes[static_cast<std::size_t>(target)].pose,
                                    found->later_in_earlier,
                                    session.graph.keyframes[static_cast<std::size_t>(node)].pose);
      m.measurement = found->later_in_earlier;
      m.information = found->information;
      m.inliers = found->inliers;
      matches.push_back(m);
      break;
    }
  }
  return matches;
}

std::optional<std::vector<SessionMerger::Match>> SessionMerger::agreeing(
    const std::vector<Match>& matches) const {
  // The largest group of placements that agree with one of them on the session's frame.
  std::vector<Match> best;
  for (const Match& centre : matches) {
    std::vector<Match> group;
    for (const Match& m : matches) {
      const Eigen::Isometry3d change = centre.transform.inverse() * m.transform;
      if (change.translation().norm() <= options_.agree_translation &&
          rotationAngle(change) <= options_.agree_rotation)
        group.push_back(m);
    }
    if (group.size() > best.size()) best = std::move(group);
  }
  if (static_cast<int>(best.size()) < options_.min_agreeing) return std::nullopt;
  return best;
}

PoseGraph::Edge SessionMerger::linkEdge(const Match& m, std::size_t offset) const {
  PoseGraph::Edge e;
  e.from = m.target;
  e.to = static_cast<int>(offset) + m.node;
  e.setMeasurement(m.measurement);
  e.setSqrtInformation(PoseGraph::sqrtInformation(m.information * settings_.loop.edge_pixels));
  e.loop = true;
  return e;
}

SessionMerger::Joined SessionMerger::join(const Session& merged, const Session& session,
                                          const std::vector<Match>& placing,
                                          const std::vector<Match>& found) const {
  const std::size_t offset = merged.graph.keyframes.size();
  const std::size_t count = session.graph.keyframes.size();
  const int first_free = static_cast<int>(offset);
  // Started where the best-supported placement puts the session; the placed keyframes held.
  const Match& start =
      *std::max_element(placing.begin(), placing.end(),
                        [](const Match& a, const Match& b) { return a.inliers < b.inliers; });
  PoseGraph graph;
  const auto optimise = [&](const std::vector<Match>& links) {
    graph = PoseGraph();
    for (const auto& k : merged.graph.keyframes) graph.addNode(k.pose);
    for (const auto& k : session.graph.keyframes) graph.addNode(start.transform * k.pose);
    for (PoseGraph::Edge e : session.graph.edges) {
      e.from += first_free;
      e.to += first_free;
      graph.addEdge(e);
    }
    for (const Match& m : links) graph.addEdge(linkEdge(m, offset));
    graph.optimise(100, first_free);
  };
  optimise(placing);

  // The other places found: each may correct the session's keyframe by what its drift since the
  // nearest placing place allows (metres walked along the session's own path).
  std::vector<double> walked(count, 0.0);
  for (std::size_t i = 1; i < count; ++i)
    walked[i] = walked[i - 1] + pathLength(session.graph.keyframes[i - 1].pose.inverse() *
                                           session.graph.keyframes[i].pose);
  Joined joined;
  joined.links = placing;
  for (const Match& m : found) {
    const bool places = std::any_of(placing.begin(), placing.end(), [&m](const Match& p) {
      return p.node == m.node && p.target == m.target;
    });
    if (places) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (const Match& p : placing)
      nearest = std::min(nearest, std::abs(walked[static_cast<std::size_t>(m.node)] -
                                           walked[static_cast<std::size_t>(p.node)]));
    const Eigen::Isometry3d correction =
        graph.pose(first_free + m.node).inverse() * graph.pose(m.target) * m.measurement;
    const double allowance = kBaseDriftAllowance + settings_.loop.drift_per_metre * nearest;
    if (correction.translation().norm() <= allowance && rotationAngle(correction) <= allowance)
      joined.links.push_back(m);
  }
  // With them, until the graph agrees with every link it keeps (a place that only looked alike
  // keeps a large residual, as a false loop does in a run).
  for (std::size_t optimised_with = placing.size(); optimised_with != joined.links.size();) {
    optimise(joined.links);
    optimised_with = joined.links.size();
    std::vector<Match> kept(placing);
    for (std::size_t k = placing.size(); k < joined.links.size(); ++k)
      if (graph.whitenedError(linkEdge(joined.links[k], offset)) <=
          settings_.loop.max_loop_residual)
        kept.push_back(joined.links[k]);
    joined.links = std::move(kept);
  }
  for (std::size_t i = 0; i < count; ++i)
    joined.poses.push_back(graph.pose(first_free + static_cast<int>(i)));
  return joined;
}

void SessionMerger::append(Session& merged, std::vector<int>& owner, int index,
                           const Session& session, const Joined& joined) const {
  const std::size_t offset = merged.graph.keyframes.size();
  const std::size_t count = session.graph.keyframes.size();
  const auto id = [offset](int node) { return static_cast<int>(offset) + node; };
  std::vector<Eigen::Isometry3d> poses = joined.poses;
  if (poses.empty())  // the first session: the merged frame is its own
    for (const auto& k : session.graph.keyframes) poses.push_back(k.pose);

  for (std::size_t i = 0; i < count; ++i)
    merged.graph.keyframes.push_back(
        {session.graph.keyframes[i].timestamp, session.graph.keyframes[i].odometry, poses[i]});
  for (PoseGraph::Edge e : session.graph.edges) {
    e.from = id(e.from);
    e.to = id(e.to);
    merged.graph.edges.push_back(e);
  }
  for (const Match& m : joined.links) merged.graph.edges.push_back(linkEdge(m, offset));
  merged.graph.places.resize(offset);
  for (std::size_t i = 0; i < count; ++i)
    merged.graph.places.push_back(i < session.graph.places.size() ? session.graph.places[i]
                                                                  : nullptr);
  for (KeyframeStore::Entry entry : session.keyframes) {
    // Anchored to a keyframe of the merged graph: its correction takes it into the merged frame.
    const int node = nodeOf(entry, count);
    if (entry.anchor < 0)  // fused as tracked: in keyframe 0's corrected frame, as its odometry
      entry.pose = session.graph.keyframes.front().odometry *
                   session.graph.keyframes.front().pose.inverse() * entry.pose;
    entry.anchor = id(node);
    merged.keyframes.push_back(std::move(entry));
  }
  // The runs' trajectories, anchored to the merged graph's keyframes as the kept keyframes are.
  for (const auto& [to, from] : {std::make_pair(&merged.frames, &session.frames),
                                 std::make_pair(&merged.fused, &session.fused)}) {
    for (const AnchoredPose& p : *from) {
      AnchoredPose a = anchoredInGraph(session, p);
      a.anchor = id(static_cast<int>(a.anchor));
      to->push_back(a);
    }
  }
  owner.insert(owner.end(), count, index);
}

Session SessionMerger::merge(const std::vector<Session>& sessions,
                             std::vector<Placement>& placements, PlaceComparisons* comparisons,
                             const std::vector<PlacedBefore>& before) const {
  placements.assign(sessions.size(), Placement{});
  Session merged;
  if (sessions.empty()) return merged;
  merged.created_by = sessions.front().created_by;
  merged.camera = sessions.front().camera;
  merged.configuration = sessions.front().configuration;
  std::vector<int> owner;  // the session each merged keyframe came from
  append(merged, owner, 0, sessions.front(), {});
  placements[0].placed = true;

  // Until a pass places no session more: one placed now may link another tried before it.
  for (bool progress = true; progress;) {
    progress = false;
    for (std::size_t i = 1; i < sessions.size(); ++i) {
      if (placements[i].placed) continue;
      static const PlacedBefore kNowhere;
      const PlacedBefore& near = i < before.size() ? before[i] : kNowhere;
      std::size_t& compared = placements[i].compared;
      std::vector<Match> matches = findMatches(merged, sessions[i], comparisons, near, compared);
      std::optional<std::vector<Match>> placing = agreeing(matches);
      if (!placing && !near.empty()) {  // not where it was: looked for everywhere
        matches = findMatches(merged, sessions[i], comparisons, {}, compared);
        placing = agreeing(matches);
      }
      if (!placing) {
        spdlog::debug("merge: session {}: {} places found, too few agreeing", i, matches.size());
        continue;
      }
      const Joined joined = join(merged, sessions[i], *placing, matches);
      spdlog::debug("merge: session {}: {} places found, {} agreeing, {} linked", i, matches.size(),
                    placing->size(), joined.links.size());
      std::map<int, int> by_owner;
      for (const Match& m : *placing) ++by_owner[owner[static_cast<std::size_t>(m.target)]];
      const std::size_t offset = merged.graph.keyframes.size();
      append(merged, owner, static_cast<int>(i), sessions[i], joined);
      Placement& p = placements[i];
      p.placed = true;
      p.first_keyframe = offset;
      p.links = static_cast<int>(joined.links.size());
      p.placing = static_cast<int>(placing->size());
      p.linked_to =
          std::max_element(by_owner.begin(), by_owner.end(), [](const auto& a, const auto& b) {
            return a.second < b.second;
          })->first;
      p.transform = placing->front().transform;  // (fitted below once the graph of all settles)
      progress = true;
    }
  }
  optimiseTogether(merged);
  // Where the graph of all put each placed session (its keyframes, fitted rigidly); the first's
  // frame is the merged one.
  for (std::size_t i = 1; i < sessions.size(); ++i) {
    const std::size_t count = sessions[i].graph.keyframes.size();
    if (!placements[i].placed || count < 3) continue;
    Eigen::Matrix3Xd before(3, count), after(3, count);
    for (std::size_t k = 0; k < count; ++k) {
      before.col(static_cast<Eigen::Index>(k)) = sessions[i].graph.keyframes[k].pose.translation();
      after.col(static_cast<Eigen::Index>(k)) =
          merged.graph.keyframes[placements[i].first_keyframe + k].pose.translation();
    }
    placements[i].transform.matrix() = Eigen::umeyama(before, after, false);
  }
  return merged;
}

void SessionMerger::optimiseTogether(Session& merged) const {
  // Each part of the graph that no edge ties to the first keyframe (a run's part after tracking
  // was lost, before it was found again) is held by its first keyframe: nothing says where else
  // it would be.
  const std::size_t n = merged.graph.keyframes.size();
  if (n < 2) return;
  std::vector<std::size_t> root(n);
  for (std::size_t i = 0; i < n; ++i) root[i] = i;
  const auto find = [&root](std::size_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  PoseGraph graph;
  for (const auto& k : merged.graph.keyframes) graph.addNode(k.pose);
  for (const PoseGraph::Edge& e : merged.graph.edges) {
    graph.addEdge(e);
    const std::size_t a = find(static_cast<std::size_t>(e.from)),
                      b = find(static_cast<std::size_t>(e.to));
    root[std::max(a, b)] = std::min(a, b);  // a part's root is its first keyframe
  }
  for (std::size_t i = 1; i < n; ++i)
    if (find(i) == i) graph.hold(static_cast<int>(i), true);
  graph.optimise(100, 1);
  for (std::size_t i = 0; i < n; ++i)
    merged.graph.keyframes[i].pose = graph.pose(static_cast<int>(i));
}

}  // namespace rgbdmap
