#include "rgbdmap/ros/cloud_message.hpp"

#include <sensor_msgs/PointField.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

namespace rgbdmap {
namespace {

sensor_msgs::PointField field(const char* name, std::uint32_t offset,
                              std::uint8_t datatype = sensor_msgs::PointField::FLOAT32) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = datatype;
  f.count = 1;
  return f;
}

// A point's x, y, z and packed rgb, 16 bytes, as both message kinds hold them.
void putPoint(const pcl::PointXYZRGB& p, std::uint8_t* out) {
  std::memcpy(out, &p.x, 4);
  std::memcpy(out + 4, &p.y, 4);
  std::memcpy(out + 8, &p.z, 4);
  std::memcpy(out + 12, &p.rgb, 4);
}

// Where the fields `names` start in each point of `msg` (found by name and type, inside the point),
// -1 for those it lacks.
template <std::size_t N>
std::array<int, N> fieldOffsets(const sensor_msgs::PointCloud2& msg,
                                const std::array<const char*, N>& names,
                                const std::array<std::uint8_t, N>& types) {
  std::array<int, N> offsets;
  offsets.fill(-1);
  for (const sensor_msgs::PointField& f : msg.fields)
    for (std::size_t i = 0; i < N; ++i)
      if (f.name == names[i] && f.datatype == types[i] && f.offset + 4 <= msg.point_step)
        offsets[i] = static_cast<int>(f.offset);
  return offsets;
}

}  // namespace

sensor_msgs::PointCloud2 toCloudMessage(const MapCloud& map, const std::string& frame_id,
                                        double stamp, std::size_t max_points) {
  constexpr std::uint32_t kStep = 16;
  // Every k-th point: blocks come out of the voxel map whole, so this thins every surface alike.
  const std::size_t every =
      max_points > 0 && map.size() > max_points ? (map.size() + max_points - 1) / max_points : 1;
  sensor_msgs::PointCloud2 msg;
  if (stamp > 0) msg.header.stamp.fromSec(stamp);
  msg.header.frame_id = frame_id;
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>((map.size() + every - 1) / every);
  msg.fields = {field("x", 0), field("y", 4), field("z", 8), field("rgb", 12)};
  msg.is_bigendian = false;
  msg.point_step = kStep;
  msg.row_step = kStep * msg.width;
  msg.is_dense = true;
  msg.data.resize(static_cast<std::size_t>(msg.row_step));
  std::uint8_t* out = msg.data.data();
  for (std::size_t i = 0; i < map.size(); i += every) {
    putPoint(map.points[i], out);
    out += kStep;
  }
  return msg;
}

bool fromCloudMessage(const sensor_msgs::PointCloud2& msg, MapCloud& map, std::string& error) {
  constexpr std::uint8_t kFloat = sensor_msgs::PointField::FLOAT32;
  const std::array<int, 4> offsets =
      fieldOffsets<4>(msg, {"x", "y", "z", "rgb"}, {kFloat, kFloat, kFloat, kFloat});
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

sensor_msgs::PointCloud2 toCellChangesMessage(const MapCloud& map, const MapCells& cells,
                                              const MapChanges::Change& change,
                                              const std::string& frame_id, double stamp) {
  constexpr std::uint32_t kStep = 28;
  std::size_t rows = change.removed.size();
  for (const std::uint64_t key : change.changed) rows += cells.cells.at(key).points.size();
  sensor_msgs::PointCloud2 msg;
  if (stamp > 0) msg.header.stamp.fromSec(stamp);
  msg.header.frame_id = frame_id;
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>(rows);
  msg.fields = {field("x", 0),
                field("y", 4),
                field("z", 8),
                field("rgb", 12),
                field("cell_x", 16, sensor_msgs::PointField::INT32),
                field("cell_y", 20, sensor_msgs::PointField::INT32),
                field("cell_z", 24, sensor_msgs::PointField::INT32)};
  msg.is_bigendian = false;
  msg.point_step = kStep;
  msg.row_step = kStep * msg.width;
  msg.is_dense = change.removed.empty();
  msg.data.resize(static_cast<std::size_t>(msg.row_step));
  std::uint8_t* out = msg.data.data();
  const auto putCell = [&out](std::uint64_t key) {
    const Eigen::Vector3i c = MapCells::coordinatesOf(key);
    std::memcpy(out + 16, c.data(), 12);
    out += kStep;
  };
  for (const std::uint64_t key : change.changed)
    for (const std::uint32_t i : cells.cells.at(key).points) {
      putPoint(map.points[i], out);
      putCell(key);
    }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const std::uint64_t key : change.removed) {
    for (int axis = 0; axis < 3; ++axis) std::memcpy(out + 4 * axis, &nan, 4);
    std::memset(out + 12, 0, 4);
    putCell(key);
  }
  return msg;
}

bool applyCellChanges(const sensor_msgs::PointCloud2& msg, CellMap& map, std::string& error) {
  constexpr std::uint8_t kFloat = sensor_msgs::PointField::FLOAT32;
  constexpr std::uint8_t kInt = sensor_msgs::PointField::INT32;
  const std::array<int, 7> offsets =
      fieldOffsets<7>(msg, {"x", "y", "z", "rgb", "cell_x", "cell_y", "cell_z"},
                      {kFloat, kFloat, kFloat, kFloat, kInt, kInt, kInt});
  for (const int offset : offsets)
    if (offset < 0) {
      error =
          "not a map's changes (fields x, y, z, rgb as float32, cell_x, cell_y, cell_z as int32)";
      return false;
    }
  if (msg.is_bigendian || msg.height != 1 ||
      msg.data.size() < static_cast<std::size_t>(msg.point_step) * msg.width) {
    error = "its size does not match its fields (" + std::to_string(msg.data.size()) + " bytes)";
    return false;
  }
  // Every cell named goes first, then gets the message's points: a cell is sent whole.
  std::vector<std::pair<CellMap::key_type, pcl::PointXYZRGB>> rows;
  rows.reserve(msg.width);
  for (std::uint32_t col = 0; col < msg.width; ++col) {
    const std::uint8_t* in = msg.data.data() + static_cast<std::size_t>(col) * msg.point_step;
    pcl::PointXYZRGB p;
    std::int32_t c[3];
    std::memcpy(&p.x, in + offsets[0], 4);
    std::memcpy(&p.y, in + offsets[1], 4);
    std::memcpy(&p.z, in + offsets[2], 4);
    std::memcpy(&p.rgb, in + offsets[3], 4);
    for (int axis = 0; axis < 3; ++axis) std::memcpy(&c[axis], in + offsets[4 + axis], 4);
    rows.push_back({{c[0], c[1], c[2]}, p});
  }
  for (const auto& [cell, p] : rows) map.erase(cell);
  for (const auto& [cell, p] : rows)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) map[cell].push_back(p);
  return true;
}

}  // namespace rgbdmap
