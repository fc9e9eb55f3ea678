// rgbdmap_node on a roscore of the test's own: bags played with `rosbag play` at the recorded
// rate, this test process as the consumer of what the nodes publish.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/UInt8MultiArray.h>
#include <std_srvs/Trigger.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <thread>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/trajectory.hpp"
#include "rgbdmap/ros/cloud_message.hpp"
#include "rgbdmap/runtime/run_signals.hpp"
#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/sessions/session_stream.hpp"
#include "ros_test_support.hpp"

namespace rgbdmap::test {
namespace {

// Tests that judge what the node maps play their bag losslessly (Pace::kNode: the player waits
// for the node), so that the node maps every frame on a slow, busy machine too. The release
// build judges the map; a sanitizer build, several times slower, checks the flow and asks for
// some map only. Tests of the live node play at the recorded rate: how many frames it drops
// depends on the machine's load (measured in bench/ros_node_drops.sh), so they check that every
// frame is accounted for and ask for some map, not for how much.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kRealTime = false;
#else
constexpr bool kRealTime = true;
#endif
const std::uint64_t kMapPoints = kRealTime ? 100000 : 1;

const char* const kRpy = "rgbd_dataset_freiburg1_rpy_head100";  // 100 pairs, 3.3 s
const char* const kXyz = "rgbd_dataset_freiburg1_xyz";          // 32 pairs, 1.1 s

// What a consumer received on one node's topics (callbacks run on a spinner thread).
struct Received {
  std::atomic<std::uint64_t> maps{0};
  std::atomic<std::uint64_t> largest_map{0};
  std::atomic<std::uint64_t> poses{0};
  std::atomic<bool> map_intact{true};
  // The occupancy grid: how many arrived, and the cells of the last one (all of the grid's
  // values are -1, 0 or 100, its size is width x height, it lies in the map's frame).
  std::atomic<std::uint64_t> grids{0}, grid_free{0}, grid_occupied{0};
  std::atomic<bool> grid_intact{true};
  ros::Subscriber map_sub, pose_sub, grid_sub;

  void subscribe(ros::NodeHandle& nh, const std::string& ns) {
    map_sub = nh.subscribe<sensor_msgs::PointCloud2>(
        ns + "/rgbdmap/map", 2, [this](const sensor_msgs::PointCloud2::ConstPtr& m) {
          // Intact: every point's bytes, the fields a PCL consumer needs.
          const bool ok = m->data.size() == static_cast<std::size_t>(m->row_step) * m->height &&
                          m->row_step == m->point_step * m->width && m->fields.size() == 4 &&
                          m->fields[0].name == "x" && m->fields[3].name == "rgb";
          if (!ok) map_intact.store(false);
          const std::uint64_t n = static_cast<std::uint64_t>(m->width) * m->height;
          if (n > largest_map.load()) largest_map.store(n);
          maps.fetch_add(1);
        });
    grid_sub = nh.subscribe<nav_msgs::OccupancyGrid>(
        ns + "/rgbdmap/grid", 2, [this, ns](const nav_msgs::OccupancyGrid::ConstPtr& g) {
          std::uint64_t free = 0, occupied = 0;
          bool ok = g->data.size() == static_cast<std::size_t>(g->info.width) * g->info.height &&
                    g->info.resolution > 0.0f &&
                    g->header.frame_id == (ns.empty() ? "map" : ns + "/map");
          for (const std::int8_t c : g->data) {
            free += c == 0;
            occupied += c == 100;
            ok = ok && (c == -1 || c == 0 || c == 100);
          }
          if (!ok) grid_intact.store(false);
          grid_free.store(free);
          grid_occupied.store(occupied);
          grids.fetch_add(1);
        });
    pose_sub = nh.subscribe<geometry_msgs::PoseStamped>(
        ns + "/rgbdmap/pose", 100,
        [this](const geometry_msgs::PoseStamped::ConstPtr&) { poses.fetch_add(1); });
  }
};

// Checks the node's end-of-run counters: every pair of images it made was mapped or counted as
// dropped (in its buffer or its queue) or skipped, none came from nowhere, and some were mapped.
// Not how many were dropped: that depends on the machine's load (bench/ros_node_drops.sh).
void expectEveryFrameAccountedFor(const std::string& stats_path, double pairs_in_bag) {
  const std::string stats = readFile(stats_path);
  ASSERT_FALSE(stats.empty()) << stats_path;
  const double received = jsonNumber(stats, "color_received");
  const double paired = jsonNumber(stats, "paired");
  const double mapped = jsonNumber(stats, "frames_processed");
  const double dropped = jsonNumber(stats, "frames_dropped") + jsonNumber(stats, "buffer_dropped");
  const double skipped = jsonNumber(stats, "frames_skipped");
  EXPECT_EQ(paired, mapped + dropped + skipped) << stats;
  EXPECT_EQ(jsonNumber(stats, "frames_captured"), mapped + jsonNumber(stats, "frames_dropped"))
      << stats;
  EXPECT_LE(paired, received) << stats;
  EXPECT_LE(paired, pairs_in_bag) << stats;
  EXPECT_GT(mapped, 0) << stats;
}

class RosNode : public RosTest {
 protected:
  // Runs the node with `params` (and ~stats: dir_/stats.json), lossless, while fr1/xyz's bag
  // plays at the pace it keeps (what it maps then does not depend on the machine's speed), stops
  // it once it has gone quiet, checks that it took and mapped every pair, and returns its log. A
  // node started from a saved session must exit 0 in a release build; a sanitizer build is not
  // judged on what it recognises (exit 1 when it never recognised the saved map, said in the
  // log).
  std::string runNodeFromSavedMap(std::vector<std::string> params) {
    const std::string node_log = dir_ + "/node.log";
    params.insert(params.begin(),
                  {nodeBinary(), "_stats:=" + dir_ + "/stats.json", "_lossless:=true"});
    Process node(params, node_log);
    auto player = play(sharedBag(kXyz), "", dir_ + "/play.log", Pace::kNode);
    EXPECT_EQ(player->wait(120), 0) << readFile(dir_ + "/play.log");
    EXPECT_TRUE(waitUntilSilent(node_log)) << readFile(node_log);
    node.signal(SIGINT);
    const int code = node.wait(60);
    const std::string log = readFile(node_log);
    if (kRealTime)
      EXPECT_EQ(code, 0) << log;
    else
      EXPECT_TRUE(code == 0 || (code == 1 && log.find("never recognised") != std::string::npos))
          << log;
    expectEveryPairTaken(node_log, 32);
    expectEveryFrameMapped(dir_ + "/stats.json", 32);
    return log;
  }
};

// A point's bytes (x, y, z, rgba), to compare maps exactly: a packed colour as a float can be NaN.
using PointBits = std::array<std::uint32_t, 4>;
PointBits bitsOf(const pcl::PointXYZRGB& p) {
  PointBits b;
  std::memcpy(&b[0], &p.x, 4);
  std::memcpy(&b[1], &p.y, 4);
  std::memcpy(&b[2], &p.z, 4);
  std::memcpy(&b[3], &p.rgba, 4);
  return b;
}

// A consumer of ~map_changes: the map it builds from them, cell by cell.
struct MapFromChanges {
  std::mutex mutex;
  CellMap cells;
  std::uint64_t messages = 0;
  std::string error;
  ros::Subscriber sub;

  void subscribe(ros::NodeHandle& nh) {
    sub = nh.subscribe<sensor_msgs::PointCloud2>(
        "/rgbdmap/map_changes", 100, [this](const sensor_msgs::PointCloud2::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex);
          if (!applyCellChanges(*m, cells, error)) ADD_FAILURE() << error;
          ++messages;
        });
  }
  // Its points, in an order that does not depend on the cells'.
  std::vector<PointBits> points() {
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<PointBits> out;
    for (const auto& [cell, points] : cells)
      for (const pcl::PointXYZRGB& p : points) out.push_back(bitsOf(p));
    std::sort(out.begin(), out.end());
    return out;
  }
};

std::vector<PointBits> sortedPoints(const MapCloud& map) {
  std::vector<PointBits> out;
  for (const pcl::PointXYZRGB& p : map.points) out.push_back(bitsOf(p));
  std::sort(out.begin(), out.end());
  return out;
}

// The node maps a bag (every frame: the player waits for it) and serves what it maps: the map
// while mapping (~map thinned to its ~map_max_points, ~map_changes whole), the grid, poses, and
// its services.
TEST_F(RosNode, MapsABagPlayedAtThePaceItKeeps) {
  const std::string bag = sharedBag(kRpy);
  Received got;
  got.subscribe(*nh_, "");
  MapFromChanges changes;
  changes.subscribe(*nh_);
  const std::string node_log = dir_ + "/node.log";
  const std::uint64_t kMaxPoints = 50000;
  std::vector<std::string> args = nodeArgs(dir_, "", Pace::kNode);
  args.push_back("_map_max_points:=" + std::to_string(kMaxPoints));
  Process node(args, node_log);
  auto player = play(bag, "", dir_ + "/play.log", Pace::kNode);
  ASSERT_EQ(player->wait(120), 0) << readFile(dir_ + "/play.log");
  // The map arrives while mapping, not only at the end: ~map thinned, ~map_changes building the
  // whole of it.
  ASSERT_TRUE(waitUntil([&] { return changes.points().size() >= kMapPoints; }, 30))
      << changes.points().size() << " points from " << changes.messages << " changes\n"
      << readFile(node_log);
  ASSERT_TRUE(
      waitUntil([&] { return got.largest_map.load() >= std::min(kMapPoints, kMaxPoints / 2); }, 30))
      << got.largest_map.load() << " points\n"
      << readFile(node_log);
  EXPECT_LE(got.largest_map.load(), kMaxPoints);
  EXPECT_TRUE(got.map_intact.load());
  EXPECT_GT(changes.messages, 1u);
  // A consumer that comes late is sent every cell first, then the changes. (roscpp gives a
  // process one connection per topic: this one's is new once the first consumer has gone.)
  changes.sub.shutdown();
  MapFromChanges late;
  late.subscribe(*nh_);
  ASSERT_TRUE(waitUntil([&] { return late.points().size() >= kMapPoints; }, 30))
      << late.points().size() << " points from " << late.messages << " changes\n"
      << readFile(node_log);

  // ~save_map answers once the map is written.
  std_srvs::Trigger save;
  ASSERT_TRUE(ros::service::call("/rgbdmap/save_map", save)) << readFile(node_log);
  EXPECT_TRUE(save.response.success) << save.response.message;
  EXPECT_GE(loadMap(dir_ + "/map.pcd").size(), kMapPoints);
  std_srvs::Trigger snapshot;
  ASSERT_TRUE(ros::service::call("/rgbdmap/snapshot", snapshot));
  EXPECT_TRUE(snapshot.response.success) << snapshot.response.message;
  // ~save_octomap writes the OctoMap beside the map and answers with its path.
  std_srvs::Trigger octomap;
  ASSERT_TRUE(ros::service::call("/rgbdmap/save_octomap", octomap));
  EXPECT_TRUE(octomap.response.success) << octomap.response.message;
  EXPECT_EQ(octomap.response.message, dir_ + "/map.bt");
  EXPECT_EQ(readFile(dir_ + "/map.bt").rfind("# Octomap OcTree binary file", 0), 0u);

  // Ctrl-C: the final map, exit 0.
  ASSERT_TRUE(waitUntilSilent(node_log)) << readFile(node_log);
  expectEveryPairTaken(node_log, 100);
  const std::uint64_t maps_before = got.maps.load();
  node.signal(SIGINT);
  ASSERT_EQ(node.wait(60), 0) << readFile(node_log);
  EXPECT_NE(readFile(node_log).find("map: "), std::string::npos);
  EXPECT_GE(loadMap(dir_ + "/map.pcd").size(), kMapPoints);
  EXPECT_GT(got.maps.load(), maps_before) << "the final map was not published";
  // What ~map_changes built is the final map, point for point.
  const std::vector<PointBits> final_map = sortedPoints(loadMap(dir_ + "/map.pcd"));
  EXPECT_TRUE(waitUntil([&] { return late.points() == final_map; }, 30))
      << late.points().size() << " points from " << late.messages << " changes, "
      << final_map.size() << " in map.pcd";
  // The grid, latched: the last one drawn from the final map (a sanitizer build may map too
  // little of the room for one).
  EXPECT_TRUE(got.grid_intact.load());
  if (kRealTime) {
    ASSERT_TRUE(waitUntil([&] { return got.grids.load() > 0; }, 30)) << readFile(node_log);
    EXPECT_GT(got.grid_free.load(), 100u);
    EXPECT_GT(got.grid_occupied.load(), 10u);
  }
  // A pose for every posed frame (tracked, or relocalised after a loss) at most, but those of
  // the first frames may go out before this consumer's connection to the new publisher is made
  // (ROS drops them: the topic is not latched), and how many depends on the machine's load.
  const std::string stats = readFile(dir_ + "/stats.json");
  const double tracked =
      jsonNumber(stats, "frames_tracked") + jsonNumber(stats, "frames_relocalised");
  EXPECT_LE(static_cast<double>(got.poses.load()), tracked) << stats;
  EXPECT_GT(got.poses.load(), 0u);
  expectEveryFrameMapped(dir_ + "/stats.json", 100);
}

// What a fleet's merger receives: the node's session as it grows, on ~session/graph and
// ~session/places, within ~session_rate; built back, it is the session the node saves.
TEST_F(RosNode, StreamsItsSessionWithinItsByteBudget) {
  const double rate = 300e3;  // bytes/s
  std::mutex mutex;
  SessionAssembler merger;
  std::uint64_t bytes = 0, largest = 0, graph_records = 0;
  bool gap = false;
  std::string refused;
  const auto receive = [&](const std::string& topic) {
    return [&, topic](const std_msgs::UInt8MultiArray::ConstPtr& m) {
      const std::string record(m->data.begin(), m->data.end());
      std::lock_guard<std::mutex> lock(mutex);
      bytes += record.size();
      largest = std::max<std::uint64_t>(largest, record.size());
      graph_records += topic == "graph";
      try {
        // The first records may go out before this subscriber is connected: ask again.
        gap = merger.apply(record, topic) == SessionAssembler::Result::kGap || gap;
      } catch (const InputError& e) {
        refused = e.what();
      }
    };
  };
  ros::Subscriber graph =
      nh_->subscribe<std_msgs::UInt8MultiArray>("/rgbdmap/session/graph", 1000, receive("graph"));
  ros::Subscriber places =
      nh_->subscribe<std_msgs::UInt8MultiArray>("/rgbdmap/session/places", 1000, receive("places"));
  ros::Subscriber pieces =
      nh_->subscribe<std_msgs::UInt8MultiArray>("/rgbdmap/session/pieces", 1000, receive("pieces"));
  const auto started = std::chrono::steady_clock::now();
  const std::string node_log = dir_ + "/node.log";
  std::vector<std::string> args = nodeArgs(dir_, "");
  args.push_back("_session_rate:=" + std::to_string(rate));
  Process node(args, node_log);
  auto player = play(sharedBag(kRpy), "", dir_ + "/play.log");
  ASSERT_EQ(player->wait(60), 0) << readFile(dir_ + "/play.log");
  ASSERT_TRUE(waitUntilSilent(node_log)) << readFile(node_log);
  std_srvs::Trigger save;
  ASSERT_TRUE(ros::service::call("/rgbdmap/save_map", save)) << readFile(node_log);
  ASSERT_TRUE(save.response.success) << save.response.message;
  const Session saved = readSession(dir_ + "/map.session");
  const std::size_t keyframes = saved.graph.keyframes.size();
  std::size_t settled = 0;  // places the stream sends (the newest keyframe's may still go)
  for (std::size_t id = 0; id + 1 < keyframes; ++id) settled += saved.graph.places[id] ? 1 : 0;
  ASSERT_GE(keyframes, 2u);
  // Everything saved arrives (asking again once if the first records were missed).
  ASSERT_TRUE(waitUntil(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        if (gap) {
          gap = false;
          std_srvs::Trigger resend;
          if (ros::service::call("/rgbdmap/session/resend", resend)) {
            EXPECT_EQ(resend.response.message, "run " + std::to_string(merger.run()));
          }
        }
        return merger.keyframes() >= keyframes && merger.places() >= settled && merger.pieces() > 0;
      },
      120))
      << merger.keyframes() << " of " << keyframes << " keyframes, " << merger.places() << " of "
      << settled << " places\n"
      << readFile(node_log);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(refused, "");
  const Session got = merger.session();
  for (std::size_t i = 0; i < keyframes; ++i) {
    EXPECT_EQ(got.graph.keyframes[i].timestamp, saved.graph.keyframes[i].timestamp);
    EXPECT_TRUE(got.graph.keyframes[i].odometry.isApprox(saved.graph.keyframes[i].odometry, 1e-12));
  }
  EXPECT_GE(got.graph.edges.size(), saved.graph.edges.size());
  for (std::size_t id = 0; id + 1 < keyframes; ++id)
    EXPECT_EQ(static_cast<bool>(got.graph.places[id]), static_cast<bool>(saved.graph.places[id]))
        << "keyframe " << id;
  // The map's pieces are keyframes the map took, as tracked (the session keeps them all here).
  for (const KeyframeStore::Entry& piece : merger.mapPieces()) {
    const auto kept = std::find_if(saved.keyframes.begin(), saved.keyframes.end(),
                                   [&](const auto& k) { return k.index == piece.index; });
    ASSERT_NE(kept, saved.keyframes.end()) << "frame " << piece.index;
    EXPECT_EQ(piece.anchor, kept->anchor);
    EXPECT_TRUE(piece.pose.isApprox(kept->pose, 1e-12));
  }
  // Within the budget: what it earned since the node started, the 2 s it may save and the one
  // place that may overdraw it.
  EXPECT_LE(static_cast<double>(bytes), rate * (seconds + 2.0) + static_cast<double>(largest))
      << bytes << " bytes in " << seconds << " s";
  EXPECT_GT(bytes, 0u);
  node.signal(SIGINT);
  ASSERT_EQ(node.wait(60), 0) << readFile(node_log);
  const std::string stats = readFile(dir_ + "/stats.json");
  EXPECT_GE(jsonNumber(stats, "session_keyframes"), static_cast<double>(keyframes)) << stats;
  EXPECT_NE(readFile(node_log).find("session stream: "), std::string::npos);
}

// Live nodes (bags at the recorded rate, as cameras send them): how much each maps depends on
// the machine, so each map is asked to arrive intact and hold points, and every frame to be
// accounted for; how much a node maps is judged losslessly (MapsABagPlayedAtThePaceItKeeps).
TEST_F(RosNode, TwoRobotsAndAConsumerOnOneMaster) {
  Received robot1, robot2;
  robot1.subscribe(*nh_, "/robot1");
  robot2.subscribe(*nh_, "/robot2");
  std::filesystem::create_directories(dir_ + "/robot1");
  std::filesystem::create_directories(dir_ + "/robot2");
  Process node1(nodeArgs(dir_ + "/robot1", "robot1"), dir_ + "/robot1/node.log");
  Process node2(nodeArgs(dir_ + "/robot2", "robot2"), dir_ + "/robot2/node.log");
  auto play1 = play(sharedBag(kRpy), "robot1", dir_ + "/robot1/play.log");
  auto play2 = play(sharedBag(kXyz), "robot2", dir_ + "/robot2/play.log");
  ASSERT_EQ(play1->wait(60), 0) << readFile(dir_ + "/robot1/play.log");
  ASSERT_EQ(play2->wait(60), 0) << readFile(dir_ + "/robot2/play.log");
  ASSERT_TRUE(waitUntil([&] { return robot1.largest_map.load() > 0; }, 30))
      << readFile(dir_ + "/robot1/node.log");
  ASSERT_TRUE(waitUntil([&] { return robot2.largest_map.load() > 0; }, 30))
      << readFile(dir_ + "/robot2/node.log");
  EXPECT_TRUE(robot1.map_intact.load());
  EXPECT_TRUE(robot2.map_intact.load());
  // Each robot's services live in its namespace.
  std_srvs::Trigger save;
  ASSERT_TRUE(ros::service::call("/robot2/rgbdmap/save_map", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  ASSERT_TRUE(waitUntilSilent(dir_ + "/robot1/node.log"));
  ASSERT_TRUE(waitUntilSilent(dir_ + "/robot2/node.log"));
  node1.signal(SIGINT);
  node2.signal(SIGINT);
  ASSERT_EQ(node1.wait(60), 0) << readFile(dir_ + "/robot1/node.log");
  ASSERT_EQ(node2.wait(60), 0) << readFile(dir_ + "/robot2/node.log");
  expectEveryFrameAccountedFor(dir_ + "/robot1/stats.json", 100);
  expectEveryFrameAccountedFor(dir_ + "/robot2/stats.json", 32);
  // Each node wrote its final map.
  EXPECT_GT(loadMap(dir_ + "/robot1/map.pcd").size(), 0u);
  EXPECT_GT(loadMap(dir_ + "/robot2/map.pcd").size(), 0u);
}

TEST_F(RosNode, LocalisesInASavedMapAndPublishesPosesInItsFrame) {
  // The saved map: fr1/rpy mapped by the command line. The node localises fr1/xyz's bag in it;
  // so does the command line, from the folder, for comparison.
  std::string output;
  const std::string cli = binary() + " --rate max --no-render --viewer none --source tum:";
  ASSERT_EQ(
      run(cli + tumDir(kRpy) + " --out " + dir_ + "/map.pcd --set pose.source=odometry", &output),
      0)
      << output;
  ASSERT_EQ(
      run(cli + tumDir(kXyz) + " --localise " + dir_ + "/map.session --out " + dir_ + "/cli.pcd",
          &output),
      0)
      << output;
  const Trajectory by_cli = Trajectory::load(dir_ + "/cli_trajectory.txt");
  const std::string map_before = readFile(dir_ + "/map.pcd");

  std::mutex mutex;
  geometry_msgs::PoseStamped last;
  ros::Subscriber poses = nh_->subscribe<geometry_msgs::PoseStamped>(
      "/rgbdmap/pose", 100, [&](const geometry_msgs::PoseStamped::ConstPtr& p) {
        std::lock_guard<std::mutex> lock(mutex);
        last = *p;
      });
  const std::string log = runNodeFromSavedMap(
      {"_out:=" + dir_ + "/localised.pcd", "_localise:=" + dir_ + "/map.session"});
  if (HasFailure()) return;
  EXPECT_NE(log.find("localising in " + dir_ + "/map.session"), std::string::npos) << log;
  // Nothing mapped, the saved map as it was.
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/localised.pcd"));
  EXPECT_EQ(readFile(dir_ + "/map.pcd"), map_before);
  const std::string stats = readFile(dir_ + "/stats.json");
  if (!kRealTime) return;
  EXPECT_NE(log.find("localisation: placed in the saved map"), std::string::npos) << log;
  EXPECT_GT(jsonNumber(stats, "keyframes_placed"), 0) << stats;
  // The last pose published is in the saved map's frame: where the command line put that frame.
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(last.header.frame_id, "map");
  const auto expected = by_cli.interpolate(last.header.stamp.toSec());
  ASSERT_TRUE(expected) << last.header.stamp.toSec();
  const Eigen::Vector3d published(last.pose.position.x, last.pose.position.y, last.pose.position.z);
  EXPECT_LT((published - expected->translation()).norm(), 0.03)
      << published.transpose() << " vs " << expected->translation().transpose();
}

TEST_F(RosNode, ContinuesASavedMapIntoOneMapAndSession) {
  // The saved map: fr1/rpy mapped by the command line. The node continues it with fr1/xyz's bag
  // (the same desk) and writes one map and one session of both.
  std::string output;
  ASSERT_EQ(run(binary() + " --rate max --no-render --viewer none --source tum:" + tumDir(kRpy) +
                    " --out " + dir_ + "/map.pcd --set pose.source=odometry",
                &output),
            0)
      << output;
  const std::string map_before = readFile(dir_ + "/map.pcd");
  const std::string log =
      runNodeFromSavedMap({"_out:=" + dir_ + "/more.pcd", "_continue:=" + dir_ + "/map.session"});
  if (HasFailure()) return;
  EXPECT_NE(log.find("continuing " + dir_ + "/map.session"), std::string::npos) << log;
  EXPECT_EQ(readFile(dir_ + "/map.pcd"), map_before);
  EXPECT_TRUE(std::filesystem::exists(dir_ + "/more.pcd")) << log;
  if (!kRealTime) return;
  EXPECT_NE(log.find("continuing: keyframe"), std::string::npos) << log;
  // One session of both runs: it holds the saved keyframes and the node's.
  ASSERT_EQ(run(binary() + " session " + dir_ + "/more.session", &output), 0) << output;
  std::string saved;
  ASSERT_EQ(run(binary() + " session " + dir_ + "/map.session", &saved), 0) << saved;
  const auto keyframes = [](const std::string& summary) {
    const auto at = summary.find("pose graph: ");
    return at == std::string::npos ? 0 : std::stoi(summary.substr(at + 12));
  };
  EXPECT_GT(keyframes(output), keyframes(saved)) << output << saved;
}

TEST_F(RosNode, BadParameterIsOneClearMessage) {
  const std::string log = dir_ + "/node.log";
  Process node({nodeBinary(), "_map/voxel_size:=-1"}, log);
  EXPECT_EQ(node.wait(60), 2) << readFile(log);
  EXPECT_NE(readFile(log).find("parameter /rgbdmap/map/voxel_size: map.voxel_size"),
            std::string::npos)
      << readFile(log);
  // A misspelt key is refused too, not ignored (parameters stay on the master: another name).
  const std::string log2 = dir_ + "/node2.log";
  Process node2({nodeBinary(), "__name:=mapper", "_map/voxel_sise:=0.005"}, log2);
  EXPECT_EQ(node2.wait(60), 2) << readFile(log2);
  EXPECT_NE(readFile(log2).find("parameter /mapper/map/voxel_sise: unknown"), std::string::npos)
      << readFile(log2);
  // A saved session to continue: not with ~localise or ~octomap, and one that is there. (Each
  // node under a name of its own: parameters stay on the master.)
  const auto refused = [&](const std::string& name, const std::vector<std::string>& params,
                           const std::string& message) {
    const std::string log3 = dir_ + "/" + name + ".log";
    std::vector<std::string> args{nodeBinary(), "__name:=" + name};
    args.insert(args.end(), params.begin(), params.end());
    Process node3(args, log3);
    EXPECT_EQ(node3.wait(60), 2) << readFile(log3);
    EXPECT_NE(readFile(log3).find(message), std::string::npos) << readFile(log3);
  };
  const std::string session = dir_ + "/saved.session";
  refused("both", {"_continue:=" + session, "_localise:=" + session},
          "parameter /both/continue: localising (/both/localise) maps nothing to continue");
  refused("octomap", {"_continue:=" + session, "_octomap:=" + dir_ + "/m.bt"},
          "parameter /octomap/continue: a session keeps no free space to go on from");
  refused("missing", {"_continue:=" + session, "_out:=" + dir_ + "/more.pcd"}, session);
  refused("thinned", {"_map_max_points:=0.5"},
          "parameter /thinned/map_max_points: must be a whole number of points >= 0");
}

TEST_F(RosNode, UnsupportedEncodingIsOneClearMessage) {
  // Two mono8 "colour" images with depth: a camera set to the wrong format.
  const std::string bag = dir_ + "/mono.bag";
  {
    rosbag::Bag b(bag, rosbag::bagmode::Write);
    for (int i = 0; i < 10; ++i) {
      sensor_msgs::Image color, depth;
      color.header.stamp.fromSec(100 + i / 30.0);
      color.header.seq = static_cast<std::uint32_t>(i);
      color.width = depth.width = 32;
      color.height = depth.height = 24;
      color.encoding = "mono8";
      color.step = 32;
      color.data.assign(32 * 24, 0);
      depth.header = color.header;
      depth.encoding = "32FC1";
      depth.step = 32 * 4;
      depth.data.assign(32 * 24 * 4, 0);
      b.write("/camera/rgb/image_color", color.header.stamp, color);
      b.write("/camera/depth/image", depth.header.stamp, depth);
    }
  }
  const std::string log = dir_ + "/node.log";
  Process node({nodeBinary(), "_out:=" + dir_ + "/map.pcd"}, log);
  std::vector<std::string> args = {"/usr/bin/rosbag", "play", "-q", "--wait-for-subscribers", bag};
  Process player(args, dir_ + "/play.log");
  EXPECT_EQ(node.wait(60), 2) << readFile(log);
  EXPECT_NE(readFile(log).find("/camera/rgb/image_color: colour encoding 'mono8' is not supported"),
            std::string::npos)
      << readFile(log);
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/map.pcd"));
  player.signal(SIGINT);
  player.wait(30);
}

// A second Ctrl-C while the final save is being written quits at once (exit 130), as the CLI's
// does, and leaves no temporary file: neither the map's (held mid-write by a StalledWrite, so the
// second interrupt finds the node writing however loaded the machine is) nor the trajectories'
// loop-closure spools.
TEST_F(RosNode, SecondSigintWhileWritingLeavesNoTemporaryFile) {
  const std::string node_log = dir_ + "/node.log";
  Process node(nodeArgs(dir_, ""), node_log);
  auto player = play(sharedBag(kXyz), "", dir_ + "/play.log");
  ASSERT_EQ(player->wait(60), 0) << readFile(dir_ + "/play.log");
  // A checkpoint: the map, both trajectories and their spools (odometry, loop closure) on disk.
  ASSERT_TRUE(ros::service::waitForService("/rgbdmap/save_map", ros::Duration(60)))
      << readFile(node_log);
  std_srvs::Trigger save;
  ASSERT_TRUE(ros::service::call("/rgbdmap/save_map", save)) << readFile(node_log);
  ASSERT_TRUE(save.response.success) << save.response.message;
  for (const char* spool : {"/map_keyframes.txt.anchored", "/map_trajectory.txt.anchored"})
    ASSERT_TRUE(std::filesystem::exists(dir_ + spool)) << spool << "\n" << readFile(node_log);

  StalledWrite map(dir_ + "/map.pcd.tmp-" + std::to_string(node.pid()));
  node.signal(SIGINT);
  ASSERT_TRUE(waitUntil(
      [&] { return readFile(node_log).find("SIGINT: stopping") != std::string::npos; }, 120))
      << readFile(node_log);
  ASSERT_TRUE(waitUntil([&] { return map.begun(); }, 120)) << readFile(node_log);
  // A second after the first was taken (its line was logged): a person's second Ctrl-C, not one
  // interrupt delivered twice (RunSignals::kSameInterrupt), whatever the machine's speed.
  std::this_thread::sleep_for(2 * RunSignals::kSameInterrupt);
  ASSERT_TRUE(node.running());
  node.signal(SIGINT);
  EXPECT_EQ(node.wait(60), 130) << readFile(node_log);
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << entry.path();
    EXPECT_EQ(name.find(".anchored"), std::string::npos) << entry.path();
  }
  EXPECT_GT(loadMap(dir_ + "/map.pcd").size(), 0u) << "the checkpoint's map stays complete";
}

}  // namespace
}  // namespace rgbdmap::test
