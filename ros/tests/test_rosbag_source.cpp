// `--source rosbag:FILE.bag`: a TUM folder written as a bag in TUM's topic layout gives the
// folder's map; 16-bit depth, pacing, camera_info, and every kind of bad input.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/ros/rosbag_source.hpp"
#include "ros_test_support.hpp"

namespace rgbdmap::test {
namespace {

const char* const kXyz = "rgbd_dataset_freiburg1_xyz";

std::string mapOptions(const std::string& out) {
  return " --rate max --no-render --viewer none -q --out " + out;
}

// The folder's ground truth given as the trajectory file, as a TUM bag user does.
std::string withGroundtruth(const std::string& tum_name) {
  return " --set pose.source=trajectory --set pose.trajectory=" + tumDir(tum_name) +
         "/groundtruth.txt";
}

// A small bag of the caller's making: `write` fills it.
std::string writeBag(const std::string& path, const std::function<void(rosbag::Bag&)>& write) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  write(bag);
  bag.close();
  return path;
}

sensor_msgs::Image image(double t, const std::string& encoding, std::uint32_t bytes_per_pixel) {
  sensor_msgs::Image msg;
  msg.header.stamp.fromSec(t);
  msg.width = 32;
  msg.height = 24;
  msg.encoding = encoding;
  msg.step = msg.width * bytes_per_pixel;
  msg.data.assign(static_cast<std::size_t>(msg.step) * msg.height, 0);
  return msg;
}

void writeImages(rosbag::Bag& bag, const std::string& color_topic, const std::string& color_enc,
                 const std::string& depth_topic, const std::string& depth_enc) {
  for (int i = 0; i < 3; ++i) {
    const double t = 100.0 + i / 30.0;
    ros::Time stamp;
    stamp.fromSec(t);
    bag.write(color_topic, stamp, image(t, color_enc, 3));
    bag.write(depth_topic, stamp, image(t, depth_enc, 4));
  }
}

TEST(RosbagSource, TumBagGivesTheFoldersMap) {
  const std::string dir = freshDir();
  const std::string bag = sharedBag(kXyz);
  std::string log;
  ASSERT_EQ(run(binary() + " --source tum:" + tumDir(kXyz) + mapOptions(dir + "/folder.pcd"), &log),
            0)
      << log;
  ASSERT_EQ(run(binary() + " --source rosbag:" + bag + withGroundtruth(kXyz) +
                    mapOptions(dir + "/bag.pcd"),
                &log),
            0)
      << log;
  EXPECT_NE(log.find("intrinsics from preset tum_fr1"), std::string::npos) << log;
  const MapCloud folder = loadMap(dir + "/folder.pcd");
  const MapCloud from_bag = loadMap(dir + "/bag.pcd");
  ASSERT_GT(folder.size(), 10000u);
  // Same pairs, same poses, same depth values: the same map, point for point.
  EXPECT_EQ(from_bag.size(), folder.size());
  EXPECT_EQ(readFile(dir + "/bag.pcd"), readFile(dir + "/folder.pcd"));
}

TEST(RosbagSource, PairsAsTheFolderDoes) {
  Config config;
  config.loadPreset("tum_fr1");
  config.replay.rate = 0;
  RosbagSource source(sharedBag(kXyz), config);
  const TumSequence folder(tumDir(kXyz));
  Frame frame;
  std::size_t n = 0;
  ReadStatus status;
  while ((status = source.read(frame)) != ReadStatus::kEnd) {
    ASSERT_EQ(status, ReadStatus::kFrame);
    ASSERT_LT(n, folder.size());
    EXPECT_NEAR(frame.timestamp, folder[n].rgb_time, 1e-6) << "frame " << n;
    EXPECT_EQ(frame.depth.type(), CV_32FC1);
    EXPECT_EQ(frame.color.type(), CV_8UC3);
    ++n;
  }
  EXPECT_EQ(n, folder.size());
}

TEST(RosbagSource, SixteenBitMillimetreDepth) {
  const std::string dir = freshDir();
  const std::string bag = sharedBag(kXyz, "--depth16", "_depth16");
  std::string log;
  ASSERT_EQ(run(binary() + " --source tum:" + tumDir(kXyz) + mapOptions(dir + "/folder.pcd"), &log),
            0)
      << log;
  ASSERT_EQ(run(binary() + " --source rosbag:" + bag + withGroundtruth(kXyz) +
                    mapOptions(dir + "/bag.pcd"),
                &log),
            0)
      << log;
  const double folder = static_cast<double>(loadMap(dir + "/folder.pcd").size());
  const double from_bag = static_cast<double>(loadMap(dir + "/bag.pcd").size());
  // Millimetres round TUM's 0.2 mm depth steps: nearly, not exactly, the same map.
  EXPECT_NEAR(from_bag, folder, 0.01 * folder);
}

TEST(RosbagSource, IntrinsicsFromCameraInfoForAnUnnamedBag) {
  const std::string dir = freshDir();
  // tum2bag writes the fr1 calibration into camera_info; a bag not named like TUM's implies no
  // preset, so camera_info gives the intrinsics.
  std::filesystem::copy_file(sharedBag(kXyz), dir + "/robot.bag");
  Config config;
  config.loadPreset("default");
  RosbagSource source(dir + "/robot.bag", config);
  Config fr1;
  fr1.loadPreset("tum_fr1");
  EXPECT_DOUBLE_EQ(source.intrinsics().fx, fr1.camera.fx);
  EXPECT_DOUBLE_EQ(source.intrinsics().cy, fr1.camera.cy);
  EXPECT_DOUBLE_EQ(source.intrinsics().k1, fr1.camera.k1);
  EXPECT_NE(source.describe().find("intrinsics from /camera/rgb/camera_info"), std::string::npos);
  // --set camera.* wins over camera_info.
  config.set("camera.fx", "600", "test");
  EXPECT_DOUBLE_EQ(RosbagSource(dir + "/robot.bag", config).intrinsics().fx, 600.0);
}

TEST(RosbagSource, PacedAtTheRecordedRate) {
  const std::string dir = freshDir();
  const auto start = std::chrono::steady_clock::now();
  std::string log;
  ASSERT_EQ(run(binary() + " --source rosbag:" + sharedBag(kXyz) + withGroundtruth(kXyz) +
                    " --rate 1 --no-render --viewer none -q --out " + dir + "/map.pcd",
                &log),
            0)
      << log;
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // The 32 pairs span 1.06 s of recording: played in no less time.
  const TumSequence folder(tumDir(kXyz));
  EXPECT_GE(took, folder[folder.size() - 1].rgb_time - folder[0].rgb_time);
}

TEST(RosbagSource, TopicsChosenByKeys) {
  const std::string dir = freshDir();
  const std::string bag = writeBag(dir + "/two_cameras.bag", [](rosbag::Bag& b) {
    writeImages(b, "/left/rgb/image", "rgb8", "/left/depth/image", "32FC1");
    writeImages(b, "/right/rgb/image", "bgr8", "/right/depth/image", "16UC1");
  });
  Config config;
  EXPECT_THROW(RosbagSource(bag, config), InputError);
  config.set("ros.color_topic", "/right/rgb/image", "test");
  config.set("ros.depth_topic", "/right/depth/image", "test");
  config.set("camera.width", "32", "test");
  config.set("camera.height", "24", "test");
  RosbagSource source(bag, config);
  Frame frame;
  EXPECT_EQ(source.read(frame), ReadStatus::kFrame);
  EXPECT_EQ(frame.depth.size(), cv::Size(32, 24));
  EXPECT_EQ(source.topics().color, "/right/rgb/image");
}

// Bad input: one clear message naming the file or topic, exit code 2, no crash.
struct BadBag {
  std::string name;
  std::function<void(const std::string& path)> make;
  std::string message;
};

TEST(RosbagSource, BadInputIsOneClearMessage) {
  const std::string dir = freshDir();
  const std::vector<BadBag> cases = {
      {"missing.bag", [](const std::string&) {}, "missing.bag: no such file"},
      {"corrupt.bag",
       [](const std::string& p) { std::ofstream(p) << "#ROSBAG V2.0\nthis is not a bag"; },
       "corrupt.bag: cannot read as a ROS bag"},
      {"text.bag", [](const std::string& p) { std::ofstream(p) << "hello"; },
       "text.bag: cannot read as a ROS bag"},
      {"no_images.bag",
       [](const std::string& p) {
         writeBag(p, [](rosbag::Bag& b) {
           sensor_msgs::CameraInfo info;
           b.write("/camera/rgb/camera_info", ros::Time(100), info);
         });
       },
       "no_images.bag: no colour image topic"},
      {"ambiguous.bag",
       [](const std::string& p) {
         writeBag(p, [](rosbag::Bag& b) {
           writeImages(b, "/a/rgb/image", "rgb8", "/a/depth/image", "32FC1");
           writeImages(b, "/b/rgb/image", "rgb8", "/b/depth/image", "32FC1");
         });
       },
       "2 topics could be the colour images (/a/rgb/image, /b/rgb/image); choose one with "
       "--set ros.color_topic=TOPIC"},
      {"mono.bag",
       [](const std::string& p) {
         writeBag(p, [](rosbag::Bag& b) {
           writeImages(b, "/camera/rgb/image_color", "mono8", "/camera/depth/image", "32FC1");
         });
       },
       "/camera/rgb/image_color: colour encoding 'mono8' is not supported"},
      {"depth_u8.bag",
       [](const std::string& p) {
         writeBag(p, [](rosbag::Bag& b) {
           writeImages(b, "/camera/rgb/image_color", "rgb8", "/camera/depth/image", "8UC1");
         });
       },
       "/camera/depth/image: depth encoding '8UC1' is not supported"},
      {"wrong_type.bag",
       [](const std::string& p) {
         writeBag(p, [](rosbag::Bag& b) {
           writeImages(b, "/camera/rgb/image_color", "rgb8", "/camera/depth/image", "32FC1");
         });
       },
       "ros.color_topic=/camera/rgb/camera_info: no such topic"},
  };
  for (const BadBag& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = dir + "/" + c.name;
    c.make(path);
    const std::string extra =
        c.name == "wrong_type.bag" ? " --set ros.color_topic=/camera/rgb/camera_info" : "";
    std::string log;
    EXPECT_EQ(run(binary() + " --source rosbag:" + path + extra + mapOptions(dir + "/m.pcd"), &log),
              2)
        << log;
    EXPECT_NE(log.find(c.message), std::string::npos) << log;
    EXPECT_EQ(log.find("Segmentation"), std::string::npos) << log;
  }
}

TEST(RosbagSource, TruncatedBagIsRefusedClearly) {
  const std::string dir = freshDir();
  // A recording killed half-way: the bag's index (at its end) is gone.
  const std::string bag = dir + "/cut.bag";
  std::filesystem::copy_file(sharedBag(kXyz), bag);
  std::filesystem::resize_file(bag, std::filesystem::file_size(bag) / 2);
  std::string log;
  const int code =
      run(binary() + " --source rosbag:" + bag + withGroundtruth(kXyz) + mapOptions(dir + "/m.pcd"),
          &log);
  // rosbag cannot open a bag without its index: a clear refusal (rosbag reindex repairs it).
  EXPECT_EQ(code, 2) << log;
  EXPECT_NE(log.find("cut.bag: cannot read as a ROS bag"), std::string::npos) << log;
  EXPECT_NE(log.find("rosbag reindex"), std::string::npos) << log;
}

}  // namespace
}  // namespace rgbdmap::test
