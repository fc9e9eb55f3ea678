#include "rgbdmap/capture/tum_sequence.hpp"

#include <algorithm>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_names.hpp"
#include "rgbdmap/base/opencv_codecs.hpp"
#include "rgbdmap/base/png_format.hpp"
#include "rgbdmap/base/text_lines.hpp"
#include "rgbdmap/capture/association.hpp"

namespace rgbdmap {
namespace {

struct ListEntry {
  double time;
  std::string path;
  std::size_t line;
};

std::vector<ListEntry> readList(const std::string& folder, const std::string& name) {
  const std::string path = folder + "/" + name;
  if (!isFile(path))
    throw InputError(path + ": missing (a TUM sequence folder needs " + name + ")");
  std::vector<ListEntry> list;
  for (const TextLine& line : readTextLines(path)) {
    if (line.fields.size() != 2)
      throw InputError(where(path, line.number) + ": expected 'timestamp filename', found " +
                       std::to_string(line.fields.size()) + " fields");
    const double t = parseNumber(line.fields[0], path, line.number, "timestamp");
    if (!list.empty() && t <= list.back().time)
      throw InputError(where(path, line.number) + ": timestamp " + line.fields[0] +
                       " is not after the previous line's");
    list.push_back({t, folder + "/" + line.fields[1], line.number});
  }
  if (list.empty()) throw InputError(path + ": no frames listed");
  return list;
}

}  // namespace

TumSequence::TumSequence(const std::string& folder, const Options& options)
    : folder_(folder), options_(options) {
  while (folder_.size() > 1 && folder_.back() == '/') folder_.pop_back();
  if (!isDirectory(folder_)) throw InputError(folder_ + ": no such folder");
  const std::vector<ListEntry> rgb = readList(folder_, "rgb.txt");
  const std::vector<ListEntry> depth = readList(folder_, "depth.txt");
  if (isFile(folder_ + "/groundtruth.txt"))
    groundtruth_ = Trajectory::load(folder_ + "/groundtruth.txt");
  if (isFile(folder_ + "/accelerometer.txt"))
    accelerometer_ = AccelerometerLog::load(folder_ + "/accelerometer.txt");

  std::vector<double> rgb_times, depth_times;
  for (const ListEntry& e : rgb) rgb_times.push_back(e.time);
  for (const ListEntry& e : depth) depth_times.push_back(e.time);
  const auto pairs = associate(rgb_times, depth_times, options_.max_difference);
  unmatched_color_ = rgb.size() - pairs.size();
  unmatched_depth_ = depth.size() - pairs.size();
  entries_.reserve(pairs.size());
  for (const auto& [i, j] : pairs) {
    TumEntry entry;
    entry.rgb_time = rgb[i].time;
    entry.depth_time = depth[j].time;
    entry.rgb_path = rgb[i].path;
    entry.depth_path = depth[j].path;
    entry.rgb_line = rgb[i].line;
    entry.depth_line = depth[j].line;
    // Ground truth is of the colour camera, so it is sampled at the colour stamp.
    entry.pose = groundtruth_.interpolate(entry.rgb_time, options_.max_pose_gap);
    entries_.push_back(std::move(entry));
  }
  if (entries_.empty())
    throw InputError(folder_ + ": no colour image has a depth image within " +
                     std::to_string(options_.max_difference) + " s");
}

std::size_t TumSequence::framesWithoutPose() const {
  std::size_t n = 0;
  for (const TumEntry& e : entries_) n += e.pose ? 0 : 1;
  return n;
}

std::string TumSequence::presetForFolder(const std::string& folder) {
  std::string name = folder;
  while (name.size() > 1 && name.back() == '/') name.pop_back();
  name = name.substr(name.find_last_of('/') + 1);  // npos + 1 == 0: no slash, whole string
  const std::string kCamera = "freiburg";
  const auto at = name.find(kCamera);
  if (at == std::string::npos || at + kCamera.size() >= name.size()) return "";
  const char n = name[at + kCamera.size()];
  return (n >= '1' && n <= '3') ? std::string("tum_fr") + n : "";
}

namespace {

template <std::size_t N>
bool startsWith(const std::vector<unsigned char>& bytes, const unsigned char (&signature)[N]) {
  return bytes.size() >= N && std::equal(signature, signature + N, bytes.begin());
}

// The container format from the first bytes, for messages and for the depth rule.
std::string imageFormat(const std::vector<unsigned char>& bytes) {
  if (startsWith(bytes, kPngSignature)) return "PNG";
  if (startsWith(bytes, {'I', 'I', '*', 0}) || startsWith(bytes, {'M', 'M', 0, '*'})) return "TIFF";
  if (startsWith(bytes, {0xff, 0xd8, 0xff})) return "JPEG";
  if (startsWith(bytes, {'B', 'M'})) return "BMP";
  return "";
}

}  // namespace

bool TumSequence::readImage(const std::string& path, ImageKind kind, cv::Mat& out,
                            std::string& error) {
  const std::string what = kind == ImageKind::kDepth ? "depth image" : "colour image";
  const auto fail = [&](const std::string& reason, const std::string& detail) {
    error = path + ": " + reason + detail;
    failure_reason_ = what + ": " + reason;
    return false;
  };
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return fail("cannot open image", "");
  const std::streamsize size = in.tellg();
  in.seekg(0);
  file_buffer_.resize(static_cast<std::size_t>(std::max<std::streamsize>(size, 0)));
  if (size <= 0 || !in.read(reinterpret_cast<char*>(file_buffer_.data()), size))
    return fail("empty or unreadable image", "");
  const std::string format = imageFormat(file_buffer_);
  // Depth is 16-bit: only PNG and TIFF hold it losslessly. Colour may be anything OpenCV reads
  // (datasets converted to the TUM layout often ship JPEG). The format is checked before
  // decoding also because imdecode leaves `out` untouched (holding the previous frame) when no
  // decoder recognises the data.
  if (kind == ImageKind::kDepth && format != "PNG" && format != "TIFF")
    return fail("depth must be a 16-bit PNG or TIFF image",
                format.empty() ? "" : " (this is " + format + ")");
  // Anything but PNG goes to OpenCV's codecs, a module loaded the first time it is needed.
  const OpenCvCodecs* codecs = nullptr;
  if (format != "PNG") {
    std::string reason;
    codecs = OpenCvCodecs::get(reason);
    if (codecs == nullptr) return fail("cannot decode image", " (" + reason + ")");
  }
  if (kind == ImageKind::kColor && format.empty() && !codecs->canRead(path))
    return fail("not an image format OpenCV can read", "");
  // The PNGs recordings are made of decode faster on our own; every other PNG gets OpenCV's
  // result as before. Either way decoding into `out` reuses its buffer when size and type match.
  PngDecoder::Status png = PngDecoder::Status::kUnsupported;
  if (format == "PNG") {
    std::string reason;
    png = png_decoder_.decode(
        file_buffer_.data(), file_buffer_.size(),
        kind == ImageKind::kDepth ? PngDecoder::Mode::kDepth : PngDecoder::Mode::kColor, out,
        reason);
    if (png == PngDecoder::Status::kCorrupt)
      return fail("cannot decode image", " (" + reason + ")");
  }
  if (png == PngDecoder::Status::kUnsupported) {
    std::string reason;
    if (codecs == nullptr) codecs = OpenCvCodecs::get(reason);
    if (codecs == nullptr) return fail("cannot decode image", " (" + reason + ")");
    if (!codecs->decode(file_buffer_.data(), file_buffer_.size(),
                        kind == ImageKind::kDepth ? cv::IMREAD_UNCHANGED : cv::IMREAD_COLOR, out,
                        reason))
      return fail("cannot decode image", " (" + reason + ")");
  }
  if (out.empty()) return fail("cannot decode image (corrupt or truncated)", "");
  if (kind == ImageKind::kDepth && out.type() != CV_16UC1)
    return fail("depth must be a 16-bit single-channel image",
                " (this " + format + " has " + std::to_string(out.elemSize1() * 8) + "-bit " +
                    std::to_string(out.channels()) + "-channel pixels)");
  return true;
}

bool TumSequence::load(std::size_t i, Frame& frame, std::string& error) {
  const TumEntry& e = entries_.at(i);
  const std::string rgb_where = where(folder_ + "/rgb.txt", e.rgb_line);
  const std::string depth_where = where(folder_ + "/depth.txt", e.depth_line);
  if (!readImage(e.depth_path, ImageKind::kDepth, raw_depth_, error)) {
    error = depth_where + ": " + error;
    return false;
  }
  if (!readImage(e.rgb_path, ImageKind::kColor, frame.color, error)) {
    error = rgb_where + ": " + error;
    return false;
  }
  if (frame.color.size() != raw_depth_.size()) {
    error = depth_where + ": " + e.depth_path + ": depth is " + std::to_string(raw_depth_.cols) +
            "x" + std::to_string(raw_depth_.rows) + " but colour " + e.rgb_path + " is " +
            std::to_string(frame.color.cols) + "x" + std::to_string(frame.color.rows);
    failure_reason_ = "depth and colour images differ in size";
    return false;
  }
  raw_depth_.convertTo(frame.depth, CV_32F, 1.0 / options_.depth_scale);
  frame.timestamp = e.rgb_time;
  frame.has_pose = e.pose.has_value();
  if (e.pose) frame.pose = *e.pose;
  const std::optional<Eigen::Vector3d> up = accelerometer_.upAt(e.rgb_time);
  frame.has_up = up.has_value();
  if (up) frame.up = *up;
  frame.origin = e.rgb_path;
  return true;
}

}  // namespace rgbdmap
