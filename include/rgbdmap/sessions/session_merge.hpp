#pragma once

#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "rgbdmap/config/config.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/slam/pose_graph.hpp"

namespace rgbdmap {

// Joins saved sessions into one, in the first one's frame (`rgbdmap merge`). A session is placed
// when enough of its kept keyframes are found among the places of the sessions placed so far
// (loop closure's verification: ORB, PnP, dense alignment) and agree on where its frame lies;
// then one pose graph is optimised over all of them: the placed sessions' keyframes held, the
// new one's free, its odometry and loop edges kept, and a loop edge for each agreeing place.
// Every other place found becomes a loop edge too once it passes loop closure's checks (within
// the drift its path from the placing places allows, then agreeing with the graph optimised
// with it): those along the session's path are what take its drift out, as the loops between
// two parts of one run would.
// A session without kept keyframes (a robot's stream) is looked for by its places instead.
// Sessions are tried again until none more can be placed, so a session linked only through
// another one joins too. A session that shares no place with the others is left out. Last, one
// graph of all the placed sessions is optimised, only the first keyframe held: a robot's stream
// holds poses as they were when sent and the loop edges that came later, and the links' errors
// are spread over every session, not left to the last one placed.
class SessionMerger {
 public:
  // Two placements agree on a session's frame within these (its own map's residual errors
  // and the placements' own).
  struct Options {
    int min_agreeing = 2;             // placements that agree, for a session to be placed
    double agree_translation = 0.05;  // m
    double agree_rotation = 0.05;     // rad
    std::size_t max_queries = 200;    // kept keyframes looked for per session and attempt
  };

  struct Placement {
    bool placed = false;
    Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  // its frame in the first's
    int links = 0;                   // places that tie it to the others (placing ones first)
    int placing = 0;                 // agreeing places it was placed by
    int linked_to = -1;              // the session (index) most of them belong to
    std::size_t first_keyframe = 0;  // its keyframes' place in the merged graph
    // Place pairs (its place, a merged one) this merge compared by appearance for the first
    // time: what placing and tying it cost (pairs compared before are remembered).
    std::size_t compared = 0;
  };

  // What comparing two places gave (places found by their places alone: a robot's stream). Kept
  // by a caller that merges the same growing sessions again and again (the fleet's merger), so
  // that each pair is compared once: a merge then costs what arrived since the last one. Holds
  // the places it has seen (their addresses are its keys).
  class PlaceComparisons {
   public:
    struct Result {
      int alike = 0;  // PlaceMatcher::similarity
      bool verified = false;
      std::optional<LoopMeasurement> found;  // PlaceMatcher::match, once verified
    };
    Result& of(const std::shared_ptr<const PlaceRecognition::Place>& target,
               const std::shared_ptr<const PlaceRecognition::Place>& query, bool& known);

   private:
    std::map<std::pair<const PlaceRecognition::Place*, const PlaceRecognition::Place*>, Result>
        results_;
    std::set<std::shared_ptr<const PlaceRecognition::Place>> held_;
  };

  // Where an earlier merge put a session's keyframes (the merged graph's poses, first keyframe
  // first; it may have more keyframes now). A session without kept keyframes that an earlier
  // merge placed is looked for only near there, as loop closure looks near a keyframe's pose:
  // each of its places is compared with the merged places within loop.search_radius (and
  // loop.max_view_angle) of where it would be, the allowance growing with the path walked since
  // the last keyframe placed; everywhere again only if that no longer places it. A merge then
  // costs what the robots sent since the last one, not every place against every place.
  using PlacedBefore = std::vector<Eigen::Isometry3d>;

  // `settings`: the first session's effective configuration (tracking, loop and filter keys).
  SessionMerger(const Config& settings, Options options);
  explicit SessionMerger(const Config& settings) : SessionMerger(settings, Options{}) {}

  // The merged session (kept keyframes, places and graph of every placed session, anchors and
  // ids renumbered) and where each input was placed.
  // `comparisons` (may be null): what earlier merges found, kept and added to. `before` (empty,
  // or one per session, empty for those not placed): where an earlier merge put them.
  Session merge(const std::vector<Session>& sessions, std::vector<Placement>& placements,
                PlaceComparisons* comparisons = nullptr,
                const std::vector<PlacedBefore>& before = {}) const;

 private:
  struct Match;
  // The session's kept keyframes found among the merged places, each with the session's frame
  // it implies.
  // `compared`: counts the pairs compared anew.
  std::vector<Match> findMatches(const Session& merged, const Session& session,
                                 PlaceComparisons* comparisons, const PlacedBefore& before,
                                 std::size_t& compared) const;
  // The same for a session without kept keyframes (streamed by a robot: no images), by its
  // places: each one looked for among the merged places (PlaceMatcher), all of them or (placed
  // `before`) those near where it would be.
  std::vector<Match> findPlaceMatches(const Session& merged, const Session& session,
                                      PlaceComparisons* comparisons, const PlacedBefore& before,
                                      std::size_t& compared) const;
  // The merged places near where `before` puts each of the session's keyframes that has a place
  // (by keyframe; nearest first).
  std::vector<std::vector<int>> nearPlaces(const Session& merged, const Session& session,
                                           const PlacedBefore& before) const;
  std::optional<std::vector<Match>> agreeing(const std::vector<Match>& matches) const;
  // Where a session placed by `placing` lies in the merged frame (its keyframes' poses), tied
  // there by `links`: the placing places and those of `found` that pass loop closure's checks.
  struct Joined {
    std::vector<Match> links;
    std::vector<Eigen::Isometry3d> poses;
  };
  Joined join(const Session& merged, const Session& session, const std::vector<Match>& placing,
              const std::vector<Match>& found) const;
  // The loop edge of a place found: from the merged keyframe to the session's (its keyframes
  // numbered from `offset`).
  PoseGraph::Edge linkEdge(const Match& m, std::size_t offset) const;
  void append(Session& merged, std::vector<int>& owner, int index, const Session& session,
              const Joined& joined) const;
  // One pose graph over every placed session's keyframes, the first keyframe held: their own
  // edges and the links between them.
  void optimiseTogether(Session& merged) const;

  Config settings_;
  Options options_;
};

}  // namespace rgbdmap
