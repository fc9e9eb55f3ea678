// rgbdmap-tum2bag: writes a TUM RGB-D folder as a ROS bag in TUM's own topic layout, as TUM
// distributes its sequences: /camera/rgb/image_color (rgb8), /camera/depth/image (32FC1 metres;
// --depth16: 16UC1 millimetres as openni2_camera records), and camera_info beside each. Every
// image listed in rgb.txt and depth.txt is written with its own stamp (not pre-paired), so that a
// reader pairs them as it would TUM's bag. Ground truth stays in groundtruth.txt, as with TUM.
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/text_lines.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/runtime/exit_code.hpp"

namespace {

using namespace rgbdmap;

struct Listed {
  double time;
  std::string path;
};

std::vector<Listed> readList(const std::string& folder, const std::string& name) {
  std::vector<Listed> list;
  for (const TextLine& line : readTextLines(folder + "/" + name)) {
    if (line.fields.size() != 2)
      throw InputError(where(folder + "/" + name, line.number) + ": expected 'timestamp file'");
    list.push_back({parseNumber(line.fields[0], folder + "/" + name, line.number, "timestamp"),
                    folder + "/" + line.fields[1]});
  }
  return list;
}

ros::Time rosTime(double seconds) {
  ros::Time t;
  t.fromSec(seconds);
  return t;
}

void fillImage(sensor_msgs::Image& msg, const cv::Mat& image, const std::string& encoding) {
  msg.height = static_cast<std::uint32_t>(image.rows);
  msg.width = static_cast<std::uint32_t>(image.cols);
  msg.encoding = encoding;
  msg.is_bigendian = 0;
  msg.step = static_cast<std::uint32_t>(image.cols * image.elemSize());
  msg.data.resize(static_cast<std::size_t>(msg.step) * image.rows);
  for (int r = 0; r < image.rows; ++r)
    std::memcpy(&msg.data[static_cast<std::size_t>(r) * msg.step], image.ptr(r), msg.step);
}

sensor_msgs::CameraInfo cameraInfo(const CameraIntrinsics& c, const std::string& frame_id) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame_id;
  info.width = static_cast<std::uint32_t>(c.width);
  info.height = static_cast<std::uint32_t>(c.height);
  info.distortion_model = "plumb_bob";
  info.D = {c.k1, c.k2, c.p1, c.p2, c.k3};
  info.K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return info;
}

int convert(const std::string& folder, const std::string& out, const std::string& preset,
            bool depth16, int limit) {
  Config config;
  config.loadPreset(preset.empty() ? [&] {
    const std::string p = TumSequence::presetForFolder(folder);
    return p.empty() ? std::string("default") : p;
  }()
                                   : preset);
  const std::vector<Listed> rgb = readList(folder, "rgb.txt");
  const std::vector<Listed> depth = readList(folder, "depth.txt");
  // Interleaved by stamp, as a recorder writes them.
  struct Item {
    double time;
    const Listed* listed;
    bool is_depth;
  };
  std::vector<Item> items;
  for (std::size_t i = 0; i < rgb.size() && (limit <= 0 || static_cast<int>(i) < limit); ++i)
    items.push_back({rgb[i].time, &rgb[i], false});
  for (std::size_t i = 0; i < depth.size() && (limit <= 0 || static_cast<int>(i) < limit); ++i)
    items.push_back({depth[i].time, &depth[i], true});
  std::stable_sort(items.begin(), items.end(),
                   [](const Item& a, const Item& b) { return a.time < b.time; });

  rosbag::Bag bag(out, rosbag::bagmode::Write);
  bag.setCompression(rosbag::compression::LZ4);
  const std::string rgb_frame = "/openni_rgb_optical_frame";
  const std::string depth_frame = "/openni_depth_optical_frame";
  // One seq counter per topic, as a camera driver's publishers keep them.
  std::uint32_t rgb_seq = 0, depth_seq = 0;
  sensor_msgs::Image msg;
  cv::Mat raw, converted;
  for (const Item& item : items) {
    const ros::Time stamp = rosTime(item.time);
    raw = cv::imread(item.listed->path, item.is_depth ? cv::IMREAD_UNCHANGED : cv::IMREAD_COLOR);
    if (raw.empty()) throw InputError(item.listed->path + ": cannot read image");
    msg.header.seq = item.is_depth ? depth_seq++ : rgb_seq++;
    msg.header.stamp = stamp;
    if (item.is_depth) {
      if (raw.type() != CV_16UC1) throw InputError(item.listed->path + ": not 16-bit depth");
      msg.header.frame_id = depth_frame;
      // The same conversion as the folder source's, so that bag and folder give one map.
      if (depth16)
        raw.convertTo(converted, CV_16U, 1000.0 / config.camera.depth_scale);
      else
        raw.convertTo(converted, CV_32F, 1.0 / config.camera.depth_scale);
      fillImage(msg, converted,
                depth16 ? sensor_msgs::image_encodings::TYPE_16UC1
                        : sensor_msgs::image_encodings::TYPE_32FC1);
      bag.write("/camera/depth/image", stamp, msg);
      sensor_msgs::CameraInfo info = cameraInfo(config.camera, depth_frame);
      info.header.stamp = stamp;
      bag.write("/camera/depth/camera_info", stamp, info);
    } else {
      msg.header.frame_id = rgb_frame;
      cv::cvtColor(raw, converted, cv::COLOR_BGR2RGB);
      fillImage(msg, converted, sensor_msgs::image_encodings::RGB8);
      bag.write("/camera/rgb/image_color", stamp, msg);
      sensor_msgs::CameraInfo info = cameraInfo(config.camera, rgb_frame);
      info.header.stamp = stamp;
      bag.write("/camera/rgb/camera_info", stamp, info);
    }
  }
  bag.close();
  spdlog::info("{}: {} colour and {} depth images from {}", out,
               std::min<std::size_t>(rgb.size(), limit > 0 ? limit : rgb.size()),
               std::min<std::size_t>(depth.size(), limit > 0 ? limit : depth.size()), folder);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rgbdmap-tum2bag: a TUM RGB-D folder as a ROS bag in TUM's topic layout"};
  std::string folder, out, preset;
  bool depth16 = false;
  int limit = 0;
  app.add_option("folder", folder, "TUM sequence folder (rgb.txt, depth.txt)")->required();
  app.add_option("out", out, "bag to write")->required();
  app.add_option("--config", preset, "preset for camera_info and depth scale (default: by name)");
  app.add_flag("--depth16", depth16, "depth as 16UC1 millimetres instead of 32FC1 metres");
  app.add_option("--limit", limit, "only the first N images of each list");
  CLI11_PARSE(app, argc, argv);
  return rgbdmap::runGuarded([&] { return convert(folder, out, preset, depth16, limit); });
}
