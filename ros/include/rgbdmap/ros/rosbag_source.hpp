#pragma once

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>

#include <chrono>
#include <memory>
#include <string>

#include "rgbdmap/capture/frame_source.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/ros/bag_topics.hpp"
#include "rgbdmap/ros/stamp_pairer.hpp"

namespace rgbdmap {

// A ROS bag replayed as a camera (`--source rosbag:FILE.bag`). Messages are read lazily through
// a rosbag::View (a chunk at a time: bags of several GB are never loaded whole); colour and depth
// are paired by header stamp with TUM's rule. rate 0: as fast as the mapper takes frames,
// losslessly; rate > 0: released at the recorded timing, the queue dropping what mapping cannot
// take, as with a live camera.
class RosbagSource : public FrameSource {
 public:
  // Throws InputError naming the bag (and topic) when it cannot be read or has no usable images.
  RosbagSource(const std::string& path, const Config& config);

  ReadStatus read(Frame& frame) override;
  CameraIntrinsics intrinsics() const override { return camera_; }
  bool isLive() const override { return rate_ > 0; }
  bool providesPoses() const override { return false; }  // bags carry no ground truth
  std::string describe() const override;
  std::uint64_t skipped() const override { return skipped_; }
  std::vector<SkipReasons::Entry> skipReasons() const override { return reasons_.entries(); }

  const BagTopics& topics() const { return topics_; }

 private:
  using ImagePtr = sensor_msgs::Image::ConstPtr;
  bool nextPair(StampPairer<ImagePtr>::Pair& pair);
  sensor_msgs::Image::ConstPtr firstImage(const std::string& topic);
  void skip(const std::string& reason, const std::string& detail);

  std::string path_;
  rosbag::Bag bag_;
  BagTopics topics_;
  CameraIntrinsics camera_;
  std::string intrinsics_from_;
  double rate_;
  std::size_t color_count_ = 0, depth_count_ = 0;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator at_;
  bool ended_ = false;
  StampPairer<ImagePtr> pairer_;
  std::uint64_t skipped_ = 0;
  SkipReasons reasons_;
  bool started_ = false;
  double first_stamp_ = 0;
  std::chrono::steady_clock::time_point start_;
};

// The bag path of a spec's rest, and the TUM preset its file name implies ("" = none).
std::string presetForBag(const std::string& path);

}  // namespace rgbdmap
