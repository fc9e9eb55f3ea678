#pragma once

// Runs of the rgbdmap program around saved sessions, for the session tests (localising in one,
// merging several): map a sequence, localise another, and read what they wrote.

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/sessions/fleet_merger.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "test_support.hpp"

namespace rgbdmap::test {

// Maps `sequence` (odometry, loop closure; lossless, so that a sanitizer build maps the same) to
// `map`, MAP.session and the trajectories beside it.
void mapTo(const std::string& sequence, const std::string& map);

// `sequence` mapped as mapTo() does, once, into a folder shared by every test and process that
// asks for it by the same name (sharedDir()/maps); returns the map's path without extension
// (PREFIX.pcd, PREFIX.session, PREFIX_keyframes.txt..., and what the program printed in
// PREFIX_log.txt). Tests read it and never write beside it (copyMap() first). The mapping
// program is $RGBDMAP_TEST_MAPPER when set: scripts/test.sh sets
// the release build's, so the sanitizer runs take the release run's maps (their tests judge what
// is done with a map; mapping runs under the sanitizers in tests of its own). The folder is named
// after that program's build, so a rebuilt program maps again.
std::string sharedMap(const std::string& name, const std::string& sequence);
// A copy of the files of map `prefix` (sharedMap()) in `dir`, named `name` instead of "map";
// returns its prefix, dir/name.
std::string copyMap(const std::string& prefix, const std::string& dir, const std::string& name);

// The session of a shared TUM folder (its name) in sharedMap().
const Session& mappedSession(const std::string& tum_name);
// mappedSession() of fr1/rpy's first 100 frames (kRpy).
inline const Session& rpySession() { return mappedSession(kRpy); }

struct SessionRun {
  int code = 0;
  std::string log, stats;  // the output, and --stats' JSON (checked to parse)
  Trajectory trajectory;   // OUT_trajectory.txt (every frame), in time order
};
// A TUM trajectory file, in time order, that may repeat a stamp: two synthetic walks share a
// clock, so a run that continues one with the other writes both runs' stamps (Trajectory::load
// refuses a repeated stamp, as no camera's clock repeats).
Trajectory loadAnyOrder(const std::string& path);
// `rgbdmap --localise session` over `sequence` (lossless), its files named after `out` (no
// extension).
SessionRun localise(const std::string& sequence, const std::string& session,
                    const std::string& out);
// `rgbdmap --continue session` over `sequence` (lossless), writing OUT.pcd, OUT.session, ...;
// `options` are added to the command line.
SessionRun continueFrom(const std::string& sequence, const std::string& session,
                        const std::string& out, const std::string& options = "");

// A file's bytes, or a folder's (every file's name and bytes): to see that nothing changed.
std::string digest(const std::string& path);

// Two trajectories as one, in time order (runs scored in one alignment).
Trajectory merged(const Trajectory& a, const Trajectory& b);

// The transform `rgbdmap merge` wrote for `session` in TRANSFORMS.txt (none: left out).
std::optional<Eigen::Isometry3d> mergedTransformOf(const std::string& transforms,
                                                   const std::string& session);

// What `rgbdmap merge SESSIONS --out OUT` did: its exit code and output, and each session's
// transform from OUT_transforms.txt (by session, in the order given; none: left out).
struct MergeRun {
  std::string out;
  int code = 0;
  std::string log;
  std::vector<std::optional<Eigen::Isometry3d>> transforms;
};
MergeRun mergeSessions(const std::vector<std::string>& sessions, const std::string& out);
// Checks that `merge` of `sessions` joined every session but `elsewhere` (which shares no place
// with them): it succeeded, said the one was left out and how many were merged, wrote a
// transform for each of the others and none for it, and its session (OUT.session) reads back.
void expectAllButOneJoined(const MergeRun& merge, const std::vector<std::string>& sessions,
                           std::size_t elsewhere);

// The points of the map `rgbdmap merge first second --out OUT` writes (both runs' kept keyframes
// fused into one TSDF): what a continued map is compared with.
std::size_t mergedPoints(const std::string& first, const std::string& second,
                         const std::string& out);

// The records a robot streams of `saved` (its graph, places and its kept keyframes as map
// pieces: SessionStream, no budget) as run `run`: what a fleet's merger receives of it.
std::vector<std::string> streamOf(const Session& saved, std::uint64_t run);
// Robot `robot` of `merger` sends `saved` as run `run` (streamOf), each record on `topic`.
// Returns how many records the merger found others missing before (SessionAssembler::kGap).
std::size_t send(FleetMerger& merger, std::size_t robot, const Session& saved, std::uint64_t run,
                 const std::string& topic);
// `saved` as a fleet's merger has it: sent as a robot streams it (graph and places, its kept
// keyframes as map pieces) and built back from the records (SessionAssembler).
Session streamed(const Session& saved);

// Where a run's frame lies in its scene: its keyframes (a TUM trajectory file) aligned to the
// ground truth's.
Eigen::Isometry3d frameInWorld(const std::string& keyframes, const std::string& truth);
// The ATE (m, RMS after a rigid alignment) of `estimate` against `truth`.
double trajectoryError(const Trajectory& estimate, const Trajectory& truth);

// `rgbdmap evaluate map`'s precision at 1 cm of an odometry map, moved by `trajectory`'s
// alignment to the scene's ground truth.
double precisionOf(const std::string& map, const std::string& scene, const std::string& trajectory);
// The same evaluation's whole score (its JSON: precision, recall, distances).
std::string scoreOf(const std::string& map, const std::string& scene,
                    const std::string& trajectory);

}  // namespace rgbdmap::test
