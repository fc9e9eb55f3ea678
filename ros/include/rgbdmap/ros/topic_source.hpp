#pragma once

#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

#include "rgbdmap/capture/frame_source.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/ros/stamp_pairer.hpp"

namespace rgbdmap {

// A camera seen through ROS topics: colour, depth and camera_info, by default
// camera/rgb/image_color, camera/depth/image and camera/rgb/camera_info in the node's namespace
// (remappable the ROS way). Callbacks (a spinner thread) only pair images by stamp and keep the
// newest few pairs; the capture thread converts them in read(). A live source: when mapping
// falls behind the oldest pairs are dropped and counted, never waited for.
// Lossless (a bag played into the node), every pair is kept until mapping takes it and the run
// is a replay's: ~intake (std_msgs/UInt64MultiArray, latched: colour images received, depth
// images received, pairs taken, the colour stamp of the last pair taken in ns) tells the player
// (rgbdmap-play) how far the node has got, so that it never runs far ahead of mapping and leaves
// once the node has received all it sent. The newest images are paired when the player is gone
// (the end of the bag), never after a mere pause.
class TopicSource : public FrameSource {
 public:
  static constexpr const char* kColorTopic = "camera/rgb/image_color";
  static constexpr const char* kDepthTopic = "camera/depth/image";
  static constexpr const char* kCameraInfoTopic = "camera/rgb/camera_info";

  TopicSource(ros::NodeHandle& nh, const Config& config, const std::atomic<bool>& stop,
              bool lossless = false);
  // Unsubscribes first (waiting for a callback in progress), before the members it uses go.
  ~TopicSource() override { shutdown(); }

  // Waits for the first colour/depth pair (and the camera_info when the intrinsics come from
  // it, for a few seconds more). Returns false when a stop came first. Throws InputError naming
  // the topic when its encoding is unusable.
  bool waitForCamera();
  // Unsubscribes: no callback touches this object afterwards.
  void shutdown();

  ReadStatus read(Frame& frame) override;
  CameraIntrinsics intrinsics() const override { return camera_; }
  bool isLive() const override { return !lossless_; }
  bool providesPoses() const override { return false; }
  std::string describe() const override;
  std::uint64_t skipped() const override;
  std::vector<SkipReasons::Entry> skipReasons() const override;
  bool canReconnect() const override { return true; }
  bool reconnect() override;

  // The colour camera's frame id (from its images), for TF.
  std::string cameraFrame() const;
  // Counters for the end-of-run summary.
  struct Counts {
    std::uint64_t color_received = 0, depth_received = 0;
    std::uint64_t color_lost = 0;  // gaps in the colour header's seq: lost before the node
    std::uint64_t paired = 0;
    std::uint64_t buffer_dropped = 0;  // pairs dropped because mapping fell behind
    std::uint64_t unmatched = 0;
  };
  Counts counts() const;

 private:
  using ImagePtr = sensor_msgs::Image::ConstPtr;
  using Pair = StampPairer<ImagePtr>::Pair;
  void onColor(const ImagePtr& msg);
  void onDepth(const ImagePtr& msg);
  void onCameraInfo(const sensor_msgs::CameraInfo::ConstPtr& msg);
  void takePairs();  // with mutex_ held
  bool waitForPair(double timeout_s);
  // For read(): until a pair is ready (true), or the input is silent (false).
  bool waitForNextPair();
  bool inputEnded() const;  // no publisher left on the image topics (the player has gone)
  void publishIntake();     // with mutex_ held
  bool flushPairs();        // pairs what is left, as at the end of a stream
  void skip(const std::string& reason, const std::string& detail);
  // What came so far, said when the images stop (a bag played to its end): the node's summary
  // at exit says the same, but a node may be stopped without one.
  void logCounts() const;

  const Config config_;
  const std::atomic<bool>& stop_;
  const bool lossless_;
  ros::Publisher intake_pub_;  // ~intake (lossless)
  std::string color_topic_, depth_topic_, info_topic_;
  ros::Subscriber color_sub_, depth_sub_, info_sub_;
  CameraIntrinsics camera_;
  std::string intrinsics_from_;

  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  StampPairer<ImagePtr> pairer_;
  std::deque<Pair> ready_;
  bool reading_ = false;  // mapping has started taking pairs
  std::optional<sensor_msgs::CameraInfo> info_;
  std::string camera_frame_;
  Counts counts_;
  std::optional<std::uint32_t> last_color_seq_;
  std::uint64_t taken_ = 0;  // pairs read() took
  ros::Time last_taken_;     // the colour stamp of the last of them
  std::uint64_t skipped_ = 0;
  SkipReasons reasons_;
};

}  // namespace rgbdmap
