#include "rgbdmap/mapping/keyframe_store.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace rgbdmap {
namespace {

constexpr double kLeverArm = 2.0;  // m
// Viewpoint distance (m) within which another kept keyframe of another visit is taken to see what
// a keyframe sees (a camera back where it was: a patrol's laps, a room crossed twice).
constexpr double kSharedViewpoint = 0.3;
// Another visit: the camera went more than this far (viewpoint distance along its way) between the
// two keyframes. Within one visit, neighbours 0.3 m apart do not see the same thing (a space
// walked once, its keyframes thinned to one per 0.3 m, lost two thirds of its surface at the next
// pass: docs/loop-closure.md), so there a view is shared only within a tenth of it (3 cm: a
// camera at rest).
constexpr double kRevisitPath = 2.0;
constexpr double kSameVisitScale = 10.0;

}  // namespace

double viewpointDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::Isometry3d moved = a.inverse() * b;
  return moved.translation().norm() + kLeverArm * Eigen::AngleAxisd(moved.linear()).angle();
}

double KeyframeStore::sharedDistance(const Entry& a, const Entry& b) {
  const double d = viewpointDistance(a.fused_at, b.fused_at);
  return std::abs(a.travelled - b.travelled) > kRevisitPath ? d : d * kSameVisitScale;
}

void KeyframeStore::findNearest(std::size_t i) {
  entries_[i].nearest = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < entries_.size(); ++j)
    if (j != i)
      entries_[i].nearest = std::min(entries_[i].nearest, sharedDistance(entries_[i], entries_[j]));
}

// Among the keyframes in memory whose view another kept one shares (sharedDistance() within
// kSharedViewpoint; a viewpoint seen once is not let go), the one whose neighbours in time are
// nearest each other: what is kept stays spread evenly over the run. (Letting go of the older of
// the two nearest viewpoints instead kept 0.94 of the synthetic walk's surface with a 64 MB budget,
// this 0.98.) None: size().
std::size_t KeyframeStore::mostRedundant() const {
  std::size_t best = entries_.size();
  double best_gap = std::numeric_limits<double>::infinity();
  // The first and the newest stay: the run's ends.
  for (std::size_t i = 1; i + 1 < entries_.size(); ++i) {
    if (entries_[i].on_disk || entries_[i].nearest > kSharedViewpoint) continue;
    // (Absolute: a continued session's keyframes follow the saved ones', whose clock may be
    // another's.)
    const double gap = std::abs(entries_[i + 1].timestamp - entries_[i - 1].timestamp);
    if (gap < best_gap) {
      best_gap = gap;
      best = i;
    }
  }
  return best;
}

// The oldest keyframe in memory but the newest (the one being added); none: size().
std::size_t KeyframeStore::oldestInMemory() const {
  for (std::size_t i = 0; i + 1 < entries_.size(); ++i)
    if (!entries_[i].on_disk) return i;
  return entries_.size();
}

// With no disk, every viewpoint unique: the one in memory nearest another, but the newest.
std::size_t KeyframeStore::nearestInMemory() const {
  std::size_t best = entries_.size();
  for (std::size_t i = 0; i + 1 < entries_.size(); ++i)
    if (!entries_[i].on_disk &&
        (best == entries_.size() || entries_[i].nearest < entries_[best].nearest))
      best = i;
  return best;
}

bool KeyframeStore::moveToDisk(std::size_t i) {
  if (disk_refused_) return false;
  Entry& e = entries_[i];
  std::string error;
  if (!spill_->append(*e.depth_png, *e.colour_png, e.disk_offset, error)) {
    spdlog::warn(
        "{}: keyframes beyond loop.keyframe_memory are let go from now on, and a pass after a "
        "loop will leave out what only they saw",
        error);
    disk_refused_ = true;
    return false;
  }
  bytes_ -= e.imageBytes();
  e.depth_bytes = e.depth_png->size();
  e.colour_bytes = e.colour_png->size();
  e.depth_png.reset();
  e.colour_png.reset();
  e.on_disk = true;
  e.disk = spill_;
  ++on_disk_;
  return true;
}

std::vector<std::size_t> KeyframeStore::fitBudget() {
  std::vector<std::size_t> let_go;
  while (bytes_ > budget_bytes_ && entries_.size() > 2) {
    std::size_t i = mostRedundant();
    if (i == entries_.size()) {
      const std::size_t oldest = oldestInMemory();
      if (oldest < entries_.size() && moveToDisk(oldest)) continue;
      i = nearestInMemory();
      if (i == entries_.size()) break;
    }
    letGo(i);
    let_go.push_back(i);
  }
  return let_go;
}

void KeyframeStore::letGo(std::size_t i) {
  bytes_ -= entries_[i].imageBytes();
  const Entry gone = std::move(entries_[i]);
  entries_.erase(entries_.begin() + static_cast<std::ptrdiff_t>(i));
  // Those whose nearest it may have been look again (the distance is not symmetric to the last
  // bit: a margin).
  for (std::size_t j = 0; j < entries_.size(); ++j)
    if (sharedDistance(entries_[j], gone) <= entries_[j].nearest * (1 + 1e-9) + 1e-12)
      findNearest(j);
}

KeyframeStore::Entry KeyframeStore::encode(const Frame& frame, const Eigen::Isometry3d& fused_at) {
  Entry e;
  e.timestamp = frame.timestamp;
  e.index = frame.index;
  e.anchor = frame.anchor;
  e.pose = frame.pose;
  e.fused_at = fused_at;
  // Each buffer keeps its type from frame to frame, so none is allocated again.
  cv::divide(kInverseDepthUnits, frame.depth, inverse_, CV_32F);           // 0 -> inf
  cv::threshold(inverse_, inverse_, 65535.0, 0.0, cv::THRESH_TOZERO_INV);  // beyond 16 bits -> 0
  inverse_.convertTo(units_, CV_16U);                                      // rounded
  cv::resize(frame.color, half_, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  // Rounded to the nearest kept level (a multiple of 4), saturating at 252.
  half_.convertTo(half_, CV_8UC3, 1.0 / (1 << kColourBitsDropped));
  cv::min(half_, cv::Scalar::all(255 >> kColourBitsDropped), half_);
  std::string error;
  std::vector<std::uint8_t> depth_png, colour_png;
  if (!encoder_.encode(units_, depth_png, error) || !encoder_.encode(half_, colour_png, error))
    throw std::runtime_error("a keyframe's images could not be kept for re-fusion: " + error);
  depth_png.shrink_to_fit();
  colour_png.shrink_to_fit();
  e.depth_png = std::make_shared<const std::vector<std::uint8_t>>(std::move(depth_png));
  e.colour_png = std::make_shared<const std::vector<std::uint8_t>>(std::move(colour_png));
  return e;
}

std::vector<std::size_t> KeyframeStore::add(const Frame& frame, const Eigen::Isometry3d& fused_at) {
  return add(encode(frame, fused_at));
}

std::vector<std::size_t> KeyframeStore::add(Entry e) {
  bytes_ += e.imageBytes();
  e.id = next_id_++;
  e.travelled = entries_.empty() ? 0.0
                                 : entries_.back().travelled +
                                       viewpointDistance(entries_.back().fused_at, e.fused_at);
  e.nearest = std::numeric_limits<double>::infinity();
  for (Entry& other : entries_) {
    const double d = sharedDistance(other, e);
    other.nearest = std::min(other.nearest, d);
    e.nearest = std::min(e.nearest, d);
  }
  entries_.push_back(std::move(e));
  return fitBudget();
}

void KeyframeStore::adopt(std::vector<Entry> earlier) {
  for (Entry& e : earlier) {
    bytes_ += e.imageBytes();
    e.id = next_id_++;
  }
  entries_.insert(entries_.begin(), std::make_move_iterator(earlier.begin()),
                  std::make_move_iterator(earlier.end()));
  // The way travelled, again in the new order (a saved session does not record it).
  for (std::size_t i = 1; i < entries_.size(); ++i)
    entries_[i].travelled = entries_[i - 1].travelled +
                            viewpointDistance(entries_[i - 1].fused_at, entries_[i].fused_at);
  for (std::size_t i = 0; i < entries_.size(); ++i) findNearest(i);
  fitBudget();
}

std::size_t KeyframeStore::find(std::uint64_t id) const {
  for (std::size_t i = 0; i < entries_.size(); ++i)
    if (entries_[i].id == id) return i;
  return entries_.size();
}

std::size_t KeyframeStore::memoryBytes() const {
  std::size_t footprints = 0;
  for (const Entry& e : entries_) footprints += e.footprint.memoryBytes();
  return bytes_ + footprints + entries_.capacity() * sizeof(Entry);
}

std::vector<KeyframeStore::Entry> KeyframeStore::entries() const { return entries_; }

namespace {

std::shared_ptr<const std::vector<std::uint8_t>> readBack(const SpillFile& disk,
                                                          std::uint64_t offset, std::size_t size) {
  std::vector<std::uint8_t> bytes;
  std::string error;
  if (!disk.read(offset, size, bytes, error)) throw std::runtime_error(error);
  return std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes));
}

}  // namespace

std::shared_ptr<const std::vector<std::uint8_t>> KeyframeStore::Entry::depthImage() const {
  return on_disk ? readBack(*disk, disk_offset, depth_bytes) : depth_png;
}

std::shared_ptr<const std::vector<std::uint8_t>> KeyframeStore::Entry::colourImage() const {
  return on_disk ? readBack(*disk, disk_offset + depth_bytes, colour_bytes) : colour_png;
}

void KeyframeStore::decode(std::size_t i, Frame& frame) { decode(entries_.at(i), frame); }

void KeyframeStore::decode(const Entry& e, Frame& frame) {
  std::string error;
  const auto depth = e.depthImage();
  const auto colour = e.colourImage();
  if (decoder_.decode(depth->data(), depth->size(), PngDecoder::Mode::kDepth, units_, error) !=
          PngDecoder::Status::kDecoded ||
      decoder_.decode(colour->data(), colour->size(), PngDecoder::Mode::kColor, half_, error) !=
          PngDecoder::Status::kDecoded)
    throw std::runtime_error("a kept keyframe's images could not be decoded: " + error);
  units_.convertTo(inverse_, CV_32F);
  cv::divide(kInverseDepthUnits, inverse_, frame.depth, CV_32F);
  frame.depth.setTo(0.0f, units_ == 0);
  half_.convertTo(half_, CV_8UC3, 1 << kColourBitsDropped);
  cv::resize(half_, frame.color, frame.depth.size(), 0.0, 0.0, cv::INTER_LINEAR);
  frame.timestamp = e.timestamp;
  frame.index = e.index;
  frame.anchor = e.anchor;
  frame.pose = e.pose;
  frame.has_pose = true;
}

}  // namespace rgbdmap
