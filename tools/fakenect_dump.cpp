#include "rgbdmap/tools/fakenect_dump.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/capture/accelerometer_log.hpp"
#include "rgbdmap/drivers/kinect_accelerometer.hpp"

namespace rgbdmap {

namespace fs = std::filesystem;

FakenectDump::FakenectDump(const std::string& dir)
    : dir_(dir),
      colour_raw_(KinectV1Model::kWidth * KinectV1Model::kHeight),
      ir_raw_(KinectV1Model::kWidth * KinectV1Model::kHeight) {
  std::error_code ec;
  if (fs::exists(fs::path(dir) / "INDEX.txt", ec))
    throw InputError(dir + ": already holds a fakenect dump (INDEX.txt); choose another --out");
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir + ": cannot create the folder (" + ec.message() + ")");
  index_.open(fs::path(dir) / "INDEX.txt");
  if (!index_) throw InputError(dir + "/INDEX.txt: cannot write (" + std::strerror(errno) + ")");
}

void FakenectDump::writeFile(const std::string& name, const std::string& header, const void* data,
                             std::size_t bytes) {
  const fs::path path = fs::path(dir_) / name;
  std::ofstream out(path, std::ios::binary);
  out << header;
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  out.close();
  if (!out) throw InputError(path.string() + ": cannot write (disk full or read-only?)");
  index_ << name << '\n';
  index_.flush();
  if (!index_) throw InputError(dir_ + "/INDEX.txt: cannot write (" + std::strerror(errno) + ")");
}

void FakenectDump::add(const Frame& frame) {
  constexpr int w = KinectV1Model::kWidth;
  constexpr int h = KinectV1Model::kHeight;
  if (frame.depth.cols != w || frame.depth.rows != h || frame.color.cols != w ||
      frame.color.rows != h || frame.depth.type() != CV_32FC1 || frame.color.type() != CV_8UC3)
    throw InputError(dir_ + ": a fakenect dump holds 640x480 Kinect v1 frames; this frame is " +
                     std::to_string(frame.depth.cols) + "x" + std::to_string(frame.depth.rows));
  for (int y = 0; y < h; ++y) {
    const float* in = frame.depth.ptr<float>(y);
    for (int x = 0; x < w; ++x) colour_raw_[y * w + x] = KinectV1Model::raw(in[x]);
  }
  model_.unregisterFromColour(colour_raw_.data(), ir_raw_.data());
  // Little-endian words, as fakenect copies them into libfreenect's buffer.
  std::vector<unsigned char> bytes(ir_raw_.size() * 2);
  for (std::size_t i = 0; i < ir_raw_.size(); ++i) {
    bytes[2 * i] = static_cast<unsigned char>(ir_raw_[i] & 0xff);
    bytes[2 * i + 1] = static_cast<unsigned char>(ir_raw_[i] >> 8);
  }
  cv::Mat rgb;
  cv::cvtColor(frame.color, rgb, cv::COLOR_BGR2RGB);
  // fakenect paces playback by the seconds field; the device stamp field is the frame number.
  char depth_name[96], colour_name[96];
  std::snprintf(depth_name, sizeof depth_name, "d-%.6f-%llu-depth.pgm", frame.timestamp,
                static_cast<unsigned long long>(frames_));
  std::snprintf(colour_name, sizeof colour_name, "r-%.6f-%llu-rgb.ppm", frame.timestamp,
                static_cast<unsigned long long>(frames_));
  if (frame.has_up) {
    // The accelerometer's reading at rest with this up (the log's samples are averaged into a
    // direction; 1 g is written), just before the depth frame it goes with.
    const Eigen::Vector3d counts =
        AccelerometerLog::upInCamera(frame.up.normalized()) * KinectAcceleration::kCountsPerG;
    FakenectTiltState state;
    state.accelerometer_x = static_cast<std::int16_t>(std::lround(counts.x()));
    state.accelerometer_y = static_cast<std::int16_t>(std::lround(counts.y()));
    state.accelerometer_z = static_cast<std::int16_t>(std::lround(counts.z()));
    char accel_name[96];
    std::snprintf(accel_name, sizeof accel_name, "a-%.6f-%llu-accel.dump", frame.timestamp,
                  static_cast<unsigned long long>(frames_));
    writeFile(accel_name, "", &state, sizeof state);
  }
  writeFile(depth_name, "P5 640 480 65535\n", bytes.data(), bytes.size());
  writeFile(colour_name, "P6 640 480 255\n", rgb.data, rgb.total() * rgb.elemSize());
  ++frames_;
}

}  // namespace rgbdmap
