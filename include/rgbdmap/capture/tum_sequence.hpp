#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/png_decoder.hpp"
#include "rgbdmap/capture/accelerometer_log.hpp"
#include "rgbdmap/capture/trajectory.hpp"

namespace rgbdmap {

// One associated colour/depth pair of a TUM sequence.
struct TumEntry {
  double rgb_time = 0.0;
  double depth_time = 0.0;
  std::string rgb_path;  // absolute or relative to the working directory
  std::string depth_path;
  std::size_t rgb_line = 0;               // line in rgb.txt, for messages
  std::size_t depth_line = 0;             // line in depth.txt
  std::optional<Eigen::Isometry3d> pose;  // interpolated ground truth, if any within max_gap
};

// A TUM RGB-D sequence folder: rgb.txt and depth.txt associated with TUM's rule and poses
// interpolated from groundtruth.txt (optional: recordings made by `rgbdmap record` have none),
// and the camera's up direction from accelerometer.txt where the folder has one.
// Behaves like a container of frames; load() decodes one into a reusable Frame.
class TumSequence {
 public:
  struct Options {
    double max_difference = 0.02;  // colour/depth association window, seconds
    double max_pose_gap = 0.05;    // a frame farther than this from ground truth gets no pose
    double depth_scale = 5000.0;   // depth units per metre
  };

  // Throws InputError naming the folder or the file and line that is wrong.
  explicit TumSequence(const std::string& folder) : TumSequence(folder, Options{}) {}
  TumSequence(const std::string& folder, const Options& options);

  std::size_t size() const { return entries_.size(); }
  const TumEntry& operator[](std::size_t i) const { return entries_[i]; }
  const std::string& folder() const { return folder_; }
  bool hasGroundtruth() const { return !groundtruth_.empty(); }
  const Trajectory& groundtruth() const { return groundtruth_; }
  std::size_t framesWithoutPose() const;
  // Colour images that found no depth partner within max_difference (and vice versa).
  std::size_t unmatchedColor() const { return unmatched_color_; }
  std::size_t unmatchedDepth() const { return unmatched_depth_; }

  // "tum_fr1", "tum_fr2", "tum_fr3" from a folder named rgbd_dataset_freiburgN_..., or "".
  static std::string presetForFolder(const std::string& folder);

  // Decodes entry i into `frame` (depth in metres, colour BGR), reusing its buffers. Colour may
  // be in any format OpenCV reads; depth must be a 16-bit PNG or TIFF. On a missing, corrupt,
  // mis-typed or mis-sized image returns false and sets `error` to a message naming the file
  // and the list line that refers to it.
  bool load(std::size_t i, Frame& frame, std::string& error);
  // Why the last load() failed, without file names ("colour image: cannot open image"), so that
  // failures can be counted by kind.
  const std::string& failureReason() const { return failure_reason_; }

 private:
  enum class ImageKind { kColor, kDepth };
  bool readImage(const std::string& path, ImageKind kind, cv::Mat& out, std::string& error);

  std::string folder_;
  Options options_;
  std::vector<TumEntry> entries_;
  Trajectory groundtruth_;
  AccelerometerLog accelerometer_;  // empty when the folder has no accelerometer.txt
  std::size_t unmatched_color_ = 0;
  std::size_t unmatched_depth_ = 0;
  std::vector<unsigned char> file_buffer_;  // reused between loads
  PngDecoder png_decoder_;                  // and its buffers
  cv::Mat raw_depth_;                       // 16-bit depth as decoded, reused
  std::string failure_reason_;
};

}  // namespace rgbdmap
