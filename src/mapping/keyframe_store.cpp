#include "rgbdmap/mapping/keyframe_store.hpp"

#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace rgbdmap {
namespace {

constexpr double kDepthUnitsPerMetre = 5000.0;  // TUM's scale: 0.2 mm, up to 13.1 m

}  // namespace

bool KeyframeStore::near(const Entry& a, const Entry& b) const {
  const Eigen::Isometry3d moved = a.fused_at.inverse() * b.fused_at;
  return moved.translation().norm() <= spacing_ &&
         Eigen::AngleAxisd(moved.linear()).angle() <= turn_;
}

void KeyframeStore::letGo(std::size_t i) {
  for (std::size_t j = 0; j < entries_.size(); ++j)
    if (j != i && near(entries_[i], entries_[j])) --entries_[j].neighbours;
  bytes_ -= entries_[i].depth_png.size() + entries_[i].colour_png.size();
  entries_.erase(entries_.begin() + static_cast<std::ptrdiff_t>(i));
}

std::vector<std::size_t> KeyframeStore::add(const Frame& frame, const Eigen::Isometry3d& fused_at) {
  Entry e;
  e.timestamp = frame.timestamp;
  e.index = frame.index;
  e.anchor = frame.anchor;
  e.pose = frame.pose;
  e.fused_at = fused_at;
  // Beyond 13.1 m (no Kinect measures that far) depth is dropped rather than wrapped.
  frame.depth.convertTo(units_, CV_32F, kDepthUnitsPerMetre);
  units_.setTo(0.0f, units_ > 65535.0f);
  units_.convertTo(units_, CV_16U);
  cv::resize(frame.color, half_, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  std::string error;
  if (!encoder_.encode(units_, e.depth_png, error) || !encoder_.encode(half_, e.colour_png, error))
    throw std::runtime_error("a keyframe's images could not be kept for re-fusion: " + error);
  e.depth_png.shrink_to_fit();
  e.colour_png.shrink_to_fit();
  bytes_ += e.depth_png.size() + e.colour_png.size();
  for (Entry& other : entries_) {
    if (near(other, e)) {
      ++other.neighbours;
      ++e.neighbours;
    }
  }
  entries_.push_back(std::move(e));
  // The most crowded viewpoint first; among equals the oldest, whose view later ones repeat.
  std::vector<std::size_t> let_go;
  while (bytes_ > budget_bytes_ && entries_.size() > 1) {
    std::size_t crowded = 0;
    for (std::size_t i = 1; i < entries_.size(); ++i)
      if (entries_[i].neighbours > entries_[crowded].neighbours) crowded = i;
    letGo(crowded);
    let_go.push_back(crowded);
  }
  return let_go;
}

void KeyframeStore::decode(std::size_t i, Frame& frame) {
  const Entry& e = entries_.at(i);
  std::string error;
  if (decoder_.decode(e.depth_png.data(), e.depth_png.size(), PngDecoder::Mode::kDepth, units_,
                      error) != PngDecoder::Status::kDecoded ||
      decoder_.decode(e.colour_png.data(), e.colour_png.size(), PngDecoder::Mode::kColor, half_,
                      error) != PngDecoder::Status::kDecoded)
    throw std::runtime_error("a kept keyframe's images could not be decoded: " + error);
  units_.convertTo(frame.depth, CV_32F, 1.0 / kDepthUnitsPerMetre);
  cv::resize(half_, frame.color, frame.depth.size(), 0.0, 0.0, cv::INTER_LINEAR);
  frame.timestamp = e.timestamp;
  frame.index = e.index;
  frame.anchor = e.anchor;
  frame.pose = e.pose;
  frame.has_pose = true;
}

}  // namespace rgbdmap
