#include "rgbdmap/ros/cloud_message.hpp"

#include <sensor_msgs/PointField.h>

#include <cmath>
#include <cstring>

namespace rgbdmap {
namespace {

sensor_msgs::PointField field(const char* name, std::uint32_t offset) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = sensor_msgs::PointField::FLOAT32;
  f.count = 1;
  return f;
}

}  // namespace

sensor_msgs::PointCloud2 toCloudMessage(const MapCloud& map, const std::string& frame_id,
                                        double stamp) {
  constexpr std::uint32_t kStep = 16;
  sensor_msgs::PointCloud2 msg;
  if (stamp > 0) msg.header.stamp.fromSec(stamp);
  msg.header.frame_id = frame_id;
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>(map.size());
  msg.fields = {field("x", 0), field("y", 4), field("z", 8), field("rgb", 12)};
  msg.is_bigendian = false;
  msg.point_step = kStep;
  msg.row_step = kStep * msg.width;
  msg.is_dense = true;
  msg.data.resize(static_cast<std::size_t>(msg.row_step));
  std::uint8_t* out = msg.data.data();
  for (const pcl::PointXYZRGB& p : map.points) {
    std::memcpy(out, &p.x, 4);
    std::memcpy(out + 4, &p.y, 4);
    std::memcpy(out + 8, &p.z, 4);
    std::memcpy(out + 12, &p.rgb, 4);
    out += kStep;
  }
  return msg;
}

bool fromCloudMessage(const sensor_msgs::PointCloud2& msg, MapCloud& map, std::string& error) {
  int offsets[4] = {-1, -1, -1, -1};
  const char* names[4] = {"x", "y", "z", "rgb"};
  for (const sensor_msgs::PointField& f : msg.fields)
    for (int i = 0; i < 4; ++i)
      if (f.name == names[i] && f.datatype == sensor_msgs::PointField::FLOAT32 &&
          f.offset + 4 <= msg.point_step)
        offsets[i] = static_cast<int>(f.offset);
  if (offsets[0] < 0 || offsets[1] < 0 || offsets[2] < 0) {
    error = "no float32 x, y and z fields";
    return false;
  }
  const std::size_t points = static_cast<std::size_t>(msg.width) * msg.height;
  if (msg.is_bigendian || msg.point_step == 0 ||
      msg.data.size() < static_cast<std::size_t>(msg.row_step) * msg.height ||
      msg.row_step < msg.point_step * msg.width) {
    error = "its size does not match its fields (" + std::to_string(msg.data.size()) + " bytes)";
    return false;
  }
  map.clear();
  map.reserve(points);
  for (std::uint32_t row = 0; row < msg.height; ++row)
    for (std::uint32_t col = 0; col < msg.width; ++col) {
      const std::uint8_t* in = msg.data.data() + static_cast<std::size_t>(row) * msg.row_step +
                               static_cast<std::size_t>(col) * msg.point_step;
      pcl::PointXYZRGB p;
      std::memcpy(&p.x, in + offsets[0], 4);
      std::memcpy(&p.y, in + offsets[1], 4);
      std::memcpy(&p.z, in + offsets[2], 4);
      if (offsets[3] >= 0) std::memcpy(&p.rgb, in + offsets[3], 4);
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) map.push_back(p);
    }
  return true;
}

}  // namespace rgbdmap
