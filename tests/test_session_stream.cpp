// A session sent live (SessionStream) and built back from its records (SessionAssembler): what a
// fleet's merger receives from a robot is the robot's graph and places, within a byte budget,
// and a damaged or foreign record is refused naming where it came from.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/sessions/map_piece.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/sessions/session_stream.hpp"
#include "session_runs.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using test::rpySession;

// A loop closer going on from the saved session: its graph and places are the session's.
struct Robot {
  explicit Robot(const Session& session)
      : closer(session.camera, TrackingOptions{}, LoopOptions{}, 0.3, 4.0, corrections, stats, true,
               &session.graph) {}
  PoseCorrections corrections;
  RunStats stats;
  LoopCloser closer;
};

bool samePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return std::memcmp(a.matrix().data(), b.matrix().data(), sizeof(double) * 16) == 0;
}

TEST(SessionStream, AMergerAssemblesTheRobotsGraphAndPlaces) {
  const Session& saved = rpySession();
  ASSERT_GE(saved.graph.keyframes.size(), 10u);
  Robot robot(saved);
  SessionStream stream(42, saved.camera, SessionStream::Options{1e12, 1.0});
  SessionAssembler merger;
  for (const SessionStream::Record& r : stream.take(robot.closer, 0.0))
    EXPECT_NE(merger.apply(r.bytes, "/robot1/session"), SessionAssembler::Result::kGap);
  EXPECT_EQ(merger.run(), 42u);
  const Session got = merger.session();
  EXPECT_EQ(got.camera.fx, saved.camera.fx);
  ASSERT_EQ(got.graph.keyframes.size(), saved.graph.keyframes.size());
  for (std::size_t i = 0; i < got.graph.keyframes.size(); ++i) {
    EXPECT_EQ(got.graph.keyframes[i].timestamp, saved.graph.keyframes[i].timestamp);
    EXPECT_TRUE(samePose(got.graph.keyframes[i].odometry, saved.graph.keyframes[i].odometry));
    // (The graph keeps a quaternion: the same pose to rounding.)
    EXPECT_TRUE(got.graph.keyframes[i].pose.isApprox(saved.graph.keyframes[i].pose, 1e-12));
  }
  ASSERT_EQ(got.graph.edges.size(), saved.graph.edges.size());
  for (std::size_t i = 0; i < got.graph.edges.size(); ++i) {
    EXPECT_EQ(got.graph.edges[i].from, saved.graph.edges[i].from);
    EXPECT_EQ(got.graph.edges[i].to, saved.graph.edges[i].to);
    EXPECT_TRUE(samePose(got.graph.edges[i].measurement(), saved.graph.edges[i].measurement()));
  }
  // Every settled place (the newest keyframe's may still be let go by the robot), whole.
  std::size_t places = 0;
  for (std::size_t id = 0; id + 1 < saved.graph.places.size(); ++id) {
    const auto& want = saved.graph.places[id];
    const auto& have = got.graph.places[id];
    ASSERT_EQ(static_cast<bool>(want), static_cast<bool>(have)) << "keyframe " << id;
    if (!want) continue;
    ++places;
    EXPECT_EQ(have->view.points.size(), want->view.points.size());
    EXPECT_EQ(cv::norm(have->view.descriptors, want->view.descriptors, cv::NORM_HAMMING), 0);
    ASSERT_EQ(have->reference.levels.size(), want->reference.levels.size());
    EXPECT_EQ(have->reference.points(), want->reference.points());
    for (std::size_t l = 0; l < want->reference.levels.size(); ++l) {
      const auto& a = have->reference.levels[l].points;
      const auto& b = want->reference.levels[l].points;
      ASSERT_EQ(a.size(), b.size());
      for (std::size_t k = 0; k < a.size(); ++k)
        ASSERT_TRUE(a[k].x == b[k].x && a[k].y == b[k].y && a[k].z == b[k].z &&
                    a[k].intensity == b[k].intensity);
    }
  }
  EXPECT_GE(places, 2u);
  EXPECT_EQ(merger.places(), places);
  // Nothing new: nothing sent.
  EXPECT_TRUE(stream.take(robot.closer, 1.0).empty());
}

TEST(SessionStream, MapPiecesGoOnceTheirAnchorHasAndArriveWhole) {
  const Session& saved = rpySession();
  ASSERT_GE(saved.keyframes.size(), 5u);
  Robot robot(saved);
  SessionStream stream(3, saved.camera, SessionStream::Options{1e12, 1.0, 1e12, 0.0});
  KeyframeStore decoder(0);
  Frame keyframe, piece;
  for (const KeyframeStore::Entry& kept : saved.keyframes) {
    decoder.decode(kept, keyframe);
    stream.addKeyframe(keyframe);
  }
  // One tracked from a keyframe the graph has not sent: it waits.
  keyframe.index = saved.keyframes.back().index + 1;
  keyframe.anchor = static_cast<std::int64_t>(saved.graph.keyframes.size());
  stream.addKeyframe(keyframe);
  SessionAssembler merger;
  for (const SessionStream::Record& r : stream.take(robot.closer, 0.0))
    EXPECT_NE(merger.apply(r.bytes, "/robot1/session"), SessionAssembler::Result::kGap);
  ASSERT_EQ(merger.pieces(), saved.keyframes.size());
  EXPECT_EQ(stream.totals().pieces, saved.keyframes.size());
  const std::vector<KeyframeStore::Entry> got = merger.mapPieces();
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].index, saved.keyframes[i].index);
    EXPECT_EQ(got[i].anchor, saved.keyframes[i].anchor);
    EXPECT_TRUE(samePose(got[i].pose, saved.keyframes[i].pose));
  }
  // A piece arrives as it was made, to the inverse-depth steps it is kept in.
  const std::size_t middle = saved.keyframes.size() / 2;
  decoder.decode(saved.keyframes[middle], keyframe);
  makeMapPiece(keyframe, piece);
  Frame arrived;
  decoder.decode(got[middle], arrived);
  ASSERT_EQ(arrived.depth.size(), piece.depth.size());
  std::size_t same = 0, measured = 0;
  for (int v = 0; v < piece.depth.rows; ++v)
    for (int u = 0; u < piece.depth.cols; ++u) {
      const float z = piece.depth.at<float>(v, u);
      if (z <= 0.0f) continue;
      ++measured;
      const double step = z * z / KeyframeStore::kInverseDepthUnits;
      same += std::abs(arrived.depth.at<float>(v, u) - z) <= 0.6 * step + 1e-5;
    }
  EXPECT_GT(measured, 2000u);
  EXPECT_EQ(same, measured);

  // Sent again (a merger asked): the same pieces, none twice.
  stream.restart();
  for (const SessionStream::Record& r : stream.take(robot.closer, 1.0))
    merger.apply(r.bytes, "/robot1/session");
  EXPECT_EQ(merger.pieces(), saved.keyframes.size());
  EXPECT_EQ(stream.totals().pieces, 2 * saved.keyframes.size());
}

TEST(SessionStream, StaysWithinItsByteBudget) {
  const Session& saved = rpySession();
  Robot robot(saved);
  const double rate = 100e3;
  SessionStream stream(7, saved.camera, SessionStream::Options{rate, 1.0});
  SessionAssembler merger;
  std::size_t settled = 0;  // places the stream sends (the newest keyframe's waits)
  for (std::size_t id = 0; id + 1 < saved.graph.places.size(); ++id)
    settled += saved.graph.places[id] ? 1 : 0;
  double now = 0.0, largest = 0.0, sent = 0.0;
  for (; merger.places() < settled; now += 0.1) {
    ASSERT_LT(now, 1000.0) << merger.places() << " of " << settled << " places arrived";
    for (const auto& r : stream.take(robot.closer, now)) {
      merger.apply(r.bytes, "/robot1/session");
      largest = std::max(largest, static_cast<double>(r.bytes.size()));
      sent += static_cast<double>(r.bytes.size());
    }
    // At most the budget earned so far, the burst and the one place that may overdraw it.
    ASSERT_LE(sent, rate * (now + 1.0) + largest) << "at " << now << " s";
  }
  // The places did not all go at once: the stream spread them out at about its rate.
  EXPECT_GT(now, 0.5 * sent / rate - 1.0);
  EXPECT_GT(now, 1.0);
  EXPECT_EQ(stream.totals().bytes, static_cast<std::uint64_t>(sent));
  EXPECT_GE(merger.places(), 2u);
  EXPECT_EQ(merger.keyframes(), saved.graph.keyframes.size());
}

TEST(SessionStream, ARestartedStreamAddsNothingTwiceAndANewRunReplacesTheOld) {
  const Session& saved = rpySession();
  Robot robot(saved);
  SessionStream stream(1, saved.camera, SessionStream::Options{1e12, 1.0});
  SessionAssembler merger;
  for (const auto& r : stream.take(robot.closer, 0.0)) merger.apply(r.bytes, "/r/session");
  const std::size_t keyframes = merger.keyframes(), edges = merger.edges(),
                    places = merger.places();
  stream.restart();
  for (const auto& r : stream.take(robot.closer, 1.0))
    EXPECT_EQ(merger.apply(r.bytes, "/r/session"), SessionAssembler::Result::kApplied);
  EXPECT_EQ(merger.keyframes(), keyframes);
  EXPECT_EQ(merger.edges(), edges);
  EXPECT_EQ(merger.places(), places);

  // The robot restarted: a new run, whose records replace the old run's.
  SessionStream again(2, saved.camera, SessionStream::Options{1e12, 1.0});
  const auto records = again.take(robot.closer, 0.0);
  ASSERT_FALSE(records.empty());
  EXPECT_EQ(merger.apply(records.front().bytes, "/r/session"), SessionAssembler::Result::kNewRun);
  EXPECT_EQ(merger.run(), 2u);
  EXPECT_EQ(merger.places(), 0u);
}

TEST(SessionStream, ADamagedOrForeignRecordIsRefusedNamingItsTopic) {
  const Session& saved = rpySession();
  Robot robot(saved);
  SessionStream stream(1, saved.camera, SessionStream::Options{1e12, 1.0});
  const auto records = stream.take(robot.closer, 0.0);
  ASSERT_GE(records.size(), 2u);
  SessionAssembler merger;
  const auto refusal = [&](const std::string& bytes) -> std::string {
    try {
      merger.apply(bytes, "/robot2/session/places");
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  std::string damaged = records[1].bytes;
  damaged[damaged.size() / 2] ^= 0x40;
  EXPECT_NE(refusal(damaged).find("/robot2/session/places: corrupt"), std::string::npos)
      << refusal(damaged);
  EXPECT_NE(refusal(records[1].bytes.substr(0, 100)).find("truncated"), std::string::npos);
  EXPECT_NE(refusal("hello").find("not a session record"), std::string::npos);
  EXPECT_EQ(merger.places(), 0u);  // nothing half-applied
}

}  // namespace
}  // namespace rgbdmap
