#include "rgbdmap/ros/rosbag_source.hpp"

#include <rosbag/exceptions.h>
#include <sensor_msgs/CameraInfo.h>
#include <spdlog/spdlog.h>

#include <thread>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_names.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/ros/image_messages.hpp"

namespace rgbdmap {
namespace {

double stampOf(const sensor_msgs::Image& msg) {
  return stampSeconds(msg.header.stamp.sec, msg.header.stamp.nsec);
}

}  // namespace

std::string presetForBag(const std::string& path) {
  // TUM names its bags like its folders: rgbd_dataset_freiburg1_xyz.bag.
  return TumSequence::presetForFolder(path);
}

RosbagSource::RosbagSource(const std::string& path, const Config& config)
    : path_(path), camera_(config.camera), rate_(config.replay.rate) {
  if (!pathExists(path)) throw InputError(path + ": no such file");
  if (!isFile(path)) throw InputError(path + ": not a file (expected a ROS bag)");
  try {
    bag_.open(path, rosbag::bagmode::Read);
    std::vector<std::pair<std::string, std::string>> topics;
    rosbag::View all(bag_);
    for (const rosbag::ConnectionInfo* c : all.getConnections())
      topics.emplace_back(c->topic, c->datatype);
    topics_ = chooseBagTopics(path, topics, rosOptions(config));

    // Checked before mapping starts, so a wrong encoding is one message, not a skipped stream.
    const ImagePtr color = firstImage(topics_.color);
    const ImagePtr depth = firstImage(topics_.depth);
    if (const std::string problem = colorEncodingProblem(color->encoding); !problem.empty())
      throw InputError(path + ": " + topics_.color + ": " + problem);
    if (const std::string problem = depthEncodingProblem(depth->encoding); !problem.empty())
      throw InputError(path + ": " + topics_.depth + ": " + problem);

    intrinsics_from_ = "preset " + config.preset;
    if (intrinsicsFromCameraInfoWanted(config)) {
      if (topics_.camera_info.empty()) {
        spdlog::warn("{}: no camera_info beside {}; using the {} preset's intrinsics", path,
                     topics_.color, config.preset);
      } else {
        rosbag::View info_view(bag_, rosbag::TopicQuery(topics_.camera_info));
        for (const rosbag::MessageInstance& m : info_view) {
          const auto info = m.instantiate<sensor_msgs::CameraInfo>();
          if (!info) continue;
          camera_ = intrinsicsFromCameraInfo(*info);
          intrinsics_from_ = topics_.camera_info;
          break;
        }
      }
    }
    if (intrinsics_from_ == topics_.camera_info &&
        (camera_.fx <= 0 || camera_.fy <= 0 || camera_.width <= 0 || camera_.height <= 0))
      throw InputError(path + ": " + topics_.camera_info + ": no usable intrinsics (K is zero)");
    color_count_ = rosbag::View(bag_, rosbag::TopicQuery(topics_.color)).size();
    depth_count_ = rosbag::View(bag_, rosbag::TopicQuery(topics_.depth)).size();
    view_ = std::make_unique<rosbag::View>(
        bag_, rosbag::TopicQuery(std::vector<std::string>{topics_.color, topics_.depth}));
    at_ = view_->begin();
  } catch (const rosbag::BagUnindexedException& e) {
    throw InputError(path + ": cannot read as a ROS bag (" + e.what() + "); `rosbag reindex " +
                     path + "` rebuilds the index of a recording cut short");
  } catch (const rosbag::BagIOException& e) {
    throw InputError(path + ": cannot read as a ROS bag (" + e.what() +
                     "); if it is a recording cut short, `rosbag reindex " + path +
                     "` rebuilds its index");
  } catch (const rosbag::BagException& e) {
    throw InputError(path + ": cannot read as a ROS bag (" + e.what() + ")");
  }
}

RosbagSource::ImagePtr RosbagSource::firstImage(const std::string& topic) {
  rosbag::View view(bag_, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    if (ImagePtr image = m.instantiate<sensor_msgs::Image>()) return image;
    throw InputError(path_ + ": " + topic + ": holds " + m.getDataType() +
                     ", not sensor_msgs/Image");
  }
  throw InputError(path_ + ": " + topic + ": no messages");
}

std::string RosbagSource::describe() const {
  return "rosbag:" + path_ + " (" + topics_.color + " " + std::to_string(color_count_) +
         " images, " + topics_.depth + " " + std::to_string(depth_count_) +
         " images, intrinsics from " + intrinsics_from_ + ")";
}

void RosbagSource::skip(const std::string& reason, const std::string& detail) {
  spdlog::warn("skipping a frame: {}", detail);
  reasons_.add(reason, detail);
  ++skipped_;
}

bool RosbagSource::nextPair(StampPairer<ImagePtr>::Pair& pair) {
  try {
    while (!ended_) {
      if (pairer_.next(pair)) return true;
      if (at_ == view_->end()) {
        ended_ = true;
        break;
      }
      const rosbag::MessageInstance& m = *at_;
      ImagePtr image = m.instantiate<sensor_msgs::Image>();
      const std::string topic = m.getTopic();
      ++at_;
      if (!image) continue;                  // checked at open: only images are on these topics
      const double stamp = stampOf(*image);  // before the move below
      if (topic == topics_.color)
        pairer_.addColor(stamp, std::move(image));
      else
        pairer_.addDepth(stamp, std::move(image));
    }
  } catch (const rosbag::BagException& e) {
    // A bag cut short (a recording that was killed) ends the stream; what was read is mapped.
    spdlog::warn("{}: cannot read further ({}); ending the replay here", path_, e.what());
    ended_ = true;
  }
  return pairer_.next(pair, true);
}

ReadStatus RosbagSource::read(Frame& frame) {
  StampPairer<ImagePtr>::Pair pair;
  if (!nextPair(pair)) return ReadStatus::kEnd;
  if (rate_ > 0) {
    if (!started_) {
      started_ = true;
      first_stamp_ = pair.color_time;
      start_ = std::chrono::steady_clock::now();
    }
    const double offset = (pair.color_time - first_stamp_) / rate_;
    std::this_thread::sleep_until(start_ +
                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(offset)));
  }
  std::string error;
  if (!depthFromMessage(*pair.depth, frame.depth, error)) {
    skip("depth image: " + error,
         topics_.depth + " at " + std::to_string(pair.depth_time) + ": " + error);
    return ReadStatus::kSkipped;
  }
  if (!colorFromMessage(*pair.color, frame.color, error)) {
    skip("colour image: " + error,
         topics_.color + " at " + std::to_string(pair.color_time) + ": " + error);
    return ReadStatus::kSkipped;
  }
  if (frame.depth.size() != frame.color.size() || frame.depth.cols != camera_.width ||
      frame.depth.rows != camera_.height) {
    skip("image size differs from the colour image or camera.width x camera.height",
         topics_.depth + " at " + std::to_string(pair.depth_time) + ": depth " +
             std::to_string(frame.depth.cols) + "x" + std::to_string(frame.depth.rows) +
             ", colour " + std::to_string(frame.color.cols) + "x" +
             std::to_string(frame.color.rows) + ", camera " + std::to_string(camera_.width) + "x" +
             std::to_string(camera_.height));
    return ReadStatus::kSkipped;
  }
  frame.timestamp = pair.color_time;
  frame.has_pose = false;
  frame.has_up = false;
  frame.origin = topics_.color + " at " + std::to_string(pair.color_time);
  return ReadStatus::kFrame;
}

}  // namespace rgbdmap
