// The live viewer: what it draws (decimation, height colours), how frames reach it without the
// mapping thread waiting, and the window itself under Xvfb (opens, shows the map's colours, q and
// closing the window both save and exit 0), and mapping without a display.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <thread>

#include "rgbdmap/viewer/display_check.hpp"
#include "rgbdmap/viewer/display_cloud.hpp"
#include "rgbdmap/viewer/viewer_mailbox.hpp"
#include "test_support.hpp"
#include "xvfb_server.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::kRpy;
using test::kXyz;
using test::XWindow;

MapCloud line(int n) {
  MapCloud cloud;
  for (int i = 0; i < n; ++i) {
    pcl::PointXYZRGB p;
    p.x = static_cast<float>(i);
    p.y = p.z = 0.0f;
    p.r = static_cast<std::uint8_t>(i % 256);
    cloud.push_back(p);
  }
  return cloud;
}

TEST(DisplayCloud, DecimatesEvenlyBeyondTheLimit) {
  DisplayCloud shown;
  shown.assign(line(10'000), 1'000);
  EXPECT_EQ(shown.map_points, 10'000u);
  EXPECT_EQ(shown.points.size(), 1'000u);
  // Every 10th point: the whole extent is still covered.
  EXPECT_EQ(shown.points.front().x(), 0.0f);
  EXPECT_EQ(shown.points.back().x(), 9'990.0f);
  EXPECT_EQ(shown.colors[1][0], 10);
}

TEST(DisplayCloud, KeepsSmallMapsWholeAndSkipsInvalidPoints) {
  MapCloud cloud = line(500);
  cloud[7].x = std::numeric_limits<float>::quiet_NaN();
  DisplayCloud shown;
  shown.assign(cloud, 1'000);
  EXPECT_EQ(shown.points.size(), 499u);
  EXPECT_EQ(shown.colors.size(), 499u);
}

TEST(DisplayCloud, HeightColorsGoFromBlueToRed) {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i <= 100; ++i) points.emplace_back(0.0f, -0.01f * static_cast<float>(i), 0.0f);
  // Up is -y (a camera's image up, TUM axes): the last point is the highest.
  const std::vector<Rgb> colors = heightColors(points, -Eigen::Vector3f::UnitY());
  EXPECT_EQ(colors.front(), (Rgb{0, 0, 255}));
  EXPECT_EQ(colors.back(), (Rgb{255, 0, 0}));
  EXPECT_EQ(colors[50][1], 255);  // green in the middle
  for (std::size_t i = 1; i < colors.size(); ++i) EXPECT_GE(colors[i][0], colors[i - 1][0]);
}

Frame frameWithColor(std::uint8_t value, double x, bool posed) {
  Frame f;
  f.color = cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(value));
  f.depth = cv::Mat(48, 64, CV_32FC1, cv::Scalar(1.0));
  f.has_pose = posed;
  f.pose.translation() = Eigen::Vector3d(x, 0, 0);
  return f;
}

TEST(ViewerMailbox, EveryPoseArrivesInOrderAndImagesAtTheViewersPace) {
  ViewerMailbox mailbox;
  PublishedStatus status;
  for (int i = 0; i < 1000; ++i) {
    status.keyframe = i % 10 == 0;
    status.frames_processed = static_cast<std::uint64_t>(i + 1);
    mailbox.publishFrame(frameWithColor(static_cast<std::uint8_t>(i % 200), i, i != 500), status);
  }
  ViewerUpdate update;
  ASSERT_TRUE(mailbox.take(update));
  ASSERT_EQ(update.new_points.size(), 999u);  // frame 500 had no pose
  for (std::size_t i = 1; i < update.new_points.size(); ++i)
    EXPECT_GT(update.new_points[i].position.x(), update.new_points[i - 1].position.x());
  EXPECT_TRUE(update.new_points[0].keyframe);
  EXPECT_FALSE(update.new_points[1].keyframe);
  EXPECT_EQ(update.pose.translation().x(), 999.0);
  EXPECT_EQ(update.status.frames_processed, 1000u);
  // Images are copied once per take, the first frame after the viewer looked.
  ASSERT_TRUE(update.has_images);
  EXPECT_EQ(update.color.at<cv::Vec3b>(0, 0)[0], 0);
  EXPECT_FALSE(mailbox.take(update));

  mailbox.publishFrame(frameWithColor(77, 1000, true), status);
  ASSERT_TRUE(mailbox.take(update));
  ASSERT_TRUE(update.has_images);
  EXPECT_EQ(update.color.at<cv::Vec3b>(0, 0)[0], 77);
  ASSERT_EQ(update.new_points.size(), 1u);
}

TEST(ViewerMailbox, WantsAMapOnlyAfterTakingTheLastOne) {
  ViewerMailbox mailbox;
  EXPECT_TRUE(mailbox.wantsMap());
  auto map = std::make_shared<MapCloud>(line(10));
  mailbox.publishMap(map);
  EXPECT_FALSE(mailbox.wantsMap());
  ViewerUpdate update;
  ASSERT_TRUE(mailbox.take(update));
  EXPECT_EQ(update.map, map);
  EXPECT_TRUE(mailbox.wantsMap());
}

TEST(ViewerMailbox, AViewerTakingConcurrentlyGetsEveryPoseInOrderAndTheLastMap) {
  ViewerMailbox mailbox;
  constexpr int kFrames = 5000;
  std::thread mapping([&] {
    PublishedStatus status;
    for (int i = 0; i < kFrames; ++i) {
      status.frames_processed = static_cast<std::uint64_t>(i + 1);
      mailbox.publishFrame(frameWithColor(static_cast<std::uint8_t>(i % 200), i, true), status);
      if (i % 500 == 499 && mailbox.wantsMap())
        mailbox.publishMap(std::make_shared<MapCloud>(line(i)));
    }
    mailbox.publishMap(std::make_shared<MapCloud>(line(kFrames)));
  });
  std::vector<double> seen;
  std::size_t last_map = 0;
  ViewerUpdate update;
  while (last_map != static_cast<std::size_t>(kFrames)) {
    if (!mailbox.take(update)) {
      std::this_thread::yield();
      continue;
    }
    for (const TrajectoryPoint& p : update.new_points) seen.push_back(p.position.x());
    if (update.map) last_map = update.map->size();
    if (update.has_images) {
      EXPECT_EQ(update.color.rows, 48);
    }
  }
  mapping.join();
  if (mailbox.take(update))
    for (const TrajectoryPoint& p : update.new_points) seen.push_back(p.position.x());
  ASSERT_EQ(seen.size(), static_cast<std::size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) ASSERT_EQ(seen[static_cast<std::size_t>(i)], i);
}

// --- The window, under Xvfb -------------------------------------------------------------------

bool waitFor(const std::function<bool()>& condition, std::chrono::seconds timeout) {
  return test::waitUntil(condition, std::chrono::duration<double>(timeout).count());
}

bool logHas(const std::string& path, const std::string& text) {
  return test::readFile(path).find(text) != std::string::npos;
}

class ViewerWindow : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { server_ = new test::XvfbServer(); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  void SetUp() override {
    if (!server_->ok()) GTEST_SKIP() << "no X server for the viewer test: " << server_->why();
  }

  // Waits for the viewer's window and for the map to be drawn in it.
  XWindow waitForMapOnScreen(const std::string& log, const std::string& title) {
    XWindow window = 0;
    EXPECT_TRUE(waitFor([&] { return logHas(log, "viewer: map on screen"); }, 120s))
        << test::readFile(log);
    EXPECT_TRUE(waitFor([&] { return (window = server_->findWindow(title)) != 0; }, 30s));
    return window;
  }

  // Of the pixels drawn in the map's part of the window (not its background), the share in the
  // colours of the saved map (quantised to 16 levels per channel).
  static std::pair<double, double> drawnAndInMapColours(const cv::Mat& shot, const MapCloud& map) {
    std::set<int> map_bins;
    for (const auto& p : map) map_bins.insert((p.r >> 4) << 8 | (p.g >> 4) << 4 | (p.b >> 4));
    const cv::Rect map_area(0, 0, shot.cols * 72 / 100, shot.rows * 95 / 100);
    const cv::Vec3b background(36, 31, 31);  // BGR of the map pane's background
    std::size_t drawn = 0, in_map = 0;
    for (int y = map_area.y; y < map_area.br().y; ++y)
      for (int x = map_area.x; x < map_area.br().x; ++x) {
        const cv::Vec3b c = shot.at<cv::Vec3b>(y, x);
        if (cv::norm(cv::Vec3i(c) - cv::Vec3i(background), cv::NORM_INF) <= 6) continue;
        ++drawn;
        in_map += map_bins.count((c[2] >> 4) << 8 | (c[1] >> 4) << 4 | (c[0] >> 4));
      }
    return {static_cast<double>(drawn) / static_cast<double>(map_area.area()),
            static_cast<double>(in_map) / static_cast<double>(std::max<std::size_t>(drawn, 1))};
  }

  // Most of what is drawn in the map's part of the window has the colours of the saved map: not
  // a blank window, not a wrong colouring.
  static void expectMapColours(const cv::Mat& shot, const MapCloud& map) {
    ASSERT_FALSE(shot.empty());
    ASSERT_GT(map.size(), 1000u);
    const auto [drawn, in_map] = drawnAndInMapColours(shot, map);
    EXPECT_GT(drawn, 0.05) << "the map pane is (nearly) blank";
    EXPECT_GT(in_map, 0.6) << "of what is drawn, only " << in_map << " has the map's colours";
  }

  std::vector<std::string> replay(const std::string& dir) {
    return {test::binary(), "--source", "tum:" + test::tumDir(kRpy), "--out", dir + "/map.pcd",
            // Slow (100 frames in 66 s): the window is up long before the replay would end by
            // itself, also on a loaded machine; q or the close button ends the run early.
            "--rate", "0.05", "--no-render", "--viewer", "auto", "--set",
            "checkpoint.every_keyframes=0", "--set", "checkpoint.every_seconds=0"};
  }

  static test::XvfbServer* server_;
};
test::XvfbServer* ViewerWindow::server_ = nullptr;

TEST_F(ViewerWindow, ReplayShowsTheMapAndQSavesAndExits) {
  const std::string dir = test::freshDir();
  const std::string log = dir + "/log.txt";
  test::Process p(replay(dir), log);
  const XWindow window = waitForMapOnScreen(log, "rgbdmap: " + dir + "/map.pcd");
  ASSERT_NE(window, 0u) << test::readFile(log);
  const cv::Mat shot = server_->screenshot(window);
  cv::imwrite(dir + "/screenshot.png", shot);  // to look at when the test fails
  server_->pressKey(window, 'q');
  EXPECT_EQ(p.wait(120), 0) << test::readFile(log);
  const std::string text = test::readFile(log);
  EXPECT_NE(text.find("viewer: q pressed"), std::string::npos) << text;
  EXPECT_NE(text.find("stopping: draining"), std::string::npos) << "q did not stop the run\n"
                                                                << text;
  expectMapColours(shot, test::loadMap(dir + "/map.pcd"));
}

TEST_F(ViewerWindow, ClosingTheWindowSavesAndExits) {
  const std::string dir = test::freshDir();
  const std::string log = dir + "/log.txt";
  test::Process p(replay(dir), log);
  const XWindow window = waitForMapOnScreen(log, "rgbdmap: " + dir + "/map.pcd");
  ASSERT_NE(window, 0u) << test::readFile(log);
  server_->closeWindow(window);
  EXPECT_EQ(p.wait(120), 0) << test::readFile(log);
  const std::string text = test::readFile(log);
  EXPECT_NE(text.find("viewer: window closed"), std::string::npos) << text;
  EXPECT_NE(text.find("stopping: draining"), std::string::npos) << text;
  EXPECT_GT(test::loadMap(dir + "/map.pcd").size(), 1000u);
}

TEST_F(ViewerWindow, ViewOpensASavedMapWithItsTrajectory) {
  const std::string dir = test::freshDir();
  ASSERT_EQ(test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --out " + dir +
                      "/map.pcd --rate max --no-render --viewer none -q"),
            0);
  const std::string log = dir + "/view.txt";
  test::Process p({test::binary(), "view", dir + "/map.pcd"}, log);
  const XWindow window = waitForMapOnScreen(log, "rgbdmap: " + dir + "/map.pcd");
  ASSERT_NE(window, 0u) << test::readFile(log);
  const cv::Mat shot = server_->screenshot(window);
  cv::imwrite(dir + "/screenshot.png", shot);  // to look at when the test fails
  expectMapColours(shot, test::loadMap(dir + "/map.pcd"));
  EXPECT_TRUE(logHas(log, "poses from " + dir + "/map_keyframes.txt")) << test::readFile(log);
  // c: the same points in a blue-to-red height ramp, no longer the map's own colours.
  server_->pressKey(window, 'c');
  ASSERT_TRUE(waitFor([&] { return logHas(log, "on screen: colour by height"); }, 60s))
      << test::readFile(log);
  const cv::Mat by_height = server_->screenshot(window);
  cv::imwrite(dir + "/screenshot_height.png", by_height);
  const auto [drawn, in_map] = drawnAndInMapColours(by_height, test::loadMap(dir + "/map.pcd"));
  EXPECT_GT(drawn, 0.01);
  EXPECT_LT(in_map, 0.5) << "coloured by height, " << in_map << " still has the map's colours";
  server_->closeWindow(window);
  EXPECT_EQ(p.wait(60), 0) << test::readFile(log);
}

TEST_F(ViewerWindow, ViewOpensASavedMesh) {
  const std::string dir = test::freshDir();
  ASSERT_EQ(
      test::run(test::binary() + " --source tum:" + test::tumDir(kXyz) + " --out " + dir +
                "/map.pcd --mesh " + dir + "/mesh.ply --rate max --no-render --viewer none -q"),
      0);
  const std::string log = dir + "/view.txt";
  test::Process p({test::binary(), "view", dir + "/mesh.ply"}, log);
  const XWindow window = waitForMapOnScreen(log, "rgbdmap: " + dir + "/mesh.ply");
  ASSERT_NE(window, 0u) << test::readFile(log);
  EXPECT_TRUE(logHas(log, "viewer: map on screen (a mesh of ")) << test::readFile(log);
  const cv::Mat shot = server_->screenshot(window);
  cv::imwrite(dir + "/screenshot.png", shot);  // to look at when the test fails
  // Shaded triangles: not the map's exact colours, but drawn, not a blank pane (measured 0.04 of
  // the pane: mesh.ply has no trajectory beside it, so the view backs off to the whole map).
  EXPECT_GT(drawnAndInMapColours(shot, test::loadMap(dir + "/map.pcd")).first, 0.02);
  server_->closeWindow(window);
  EXPECT_EQ(p.wait(60), 0) << test::readFile(log);
}

TEST(ViewerNoDisplay, AutoMapsWithoutAViewerAndSaysSoOnce) {
  const std::string dir = test::freshDir();
  std::string output;
  ASSERT_EQ(test::run("env -u DISPLAY " + test::binary() + " --source tum:" + test::tumDir(kXyz) +
                          " --out " + dir + "/map.pcd --rate max --no-render --viewer auto -q",
                      &output),
            0)
      << output;
  std::size_t said = 0;
  for (std::size_t at = output.find("viewer: no display"); at != std::string::npos;
       at = output.find("viewer: no display", at + 1))
    ++said;
  EXPECT_EQ(said, 1u) << output;
  EXPECT_NE(output.find("DISPLAY is not set"), std::string::npos) << output;
  EXPECT_GT(test::loadMap(dir + "/map.pcd").size(), 1000u);
}

TEST(ViewerNoDisplay, ViewWithoutADisplayIsAClearError) {
  std::string output;
  EXPECT_EQ(test::run("env -u DISPLAY " + test::binary() + " view " + test::dataDir() +
                          "/no-such-map.pcd",
                      &output),
            2);
  EXPECT_NE(output.find("no display"), std::string::npos) << output;
}

}  // namespace
}  // namespace rgbdmap
