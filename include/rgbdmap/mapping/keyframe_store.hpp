#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/png_decoder.hpp"
#include "rgbdmap/base/png_encoder.hpp"
#include "rgbdmap/mapping/keyframe_footprint.hpp"
#include "rgbdmap/mapping/spill_file.hpp"

namespace rgbdmap {

// How far apart two camera poses see things: the translation plus the turn times a 2 m lever arm
// (how far a point 2 m in front of the camera moves).
double viewpointDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);

// The keyframes the map is made of, their images kept compressed, so that the map can be fused
// again when loop closure moves their poses (Mapper). Depth is kept as PNG in steps of inverse
// depth half the sensor's noise, colour as PNG at half the resolution and 6 bits a channel (a
// voxel at 1 m spans five pixels; colour does not move surfaces): about 0.16 MB a keyframe of
// TUM's at 640 x 480, 0.3 MB a synthetic one (its noise is not quantised as a Kinect's is).
//
// Memory is bounded: every keyframe's images are kept in memory while they fit in
// `budget_bytes`. Beyond it, one keyframe at a time gives up its place: among those whose
// viewpoint another kept keyframe shares (one of another visit within 0.3 m, a turn counting 2 m
// per radian, or one of the same visit within 3 cm; poses as corrected when they were fused), the
// one whose neighbours in time are nearest each other is let go; when every viewpoint in memory
// is unique, the oldest one's images move to a scratch file on disk (SpillFile), from which a
// pass reads them back. So a short run keeps every keyframe in memory (its map re-fuses exactly);
// a space walked once keeps every view (on disk beyond the budget), and a camera at rest or
// walking laps round a room thins what it has seen again and again. (Thinning views 0.3 m apart
// within one visit lost two thirds of a large room's surface at a pass: docs/loop-closure.md.)
// Should the disk refuse, the store says so once and lets the oldest unique views go.
class KeyframeStore {
 public:
  struct Entry {
    std::uint64_t id = 0;  // the store's own, unique in it (indices shift as keyframes go)
    double timestamp = 0.0;
    std::uint64_t index = 0;
    std::int64_t anchor = -1;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();      // as tracked (odometry)
    Eigen::Isometry3d fused_at = Eigen::Isometry3d::Identity();  // in the map, corrected
    // Shared and never changed once encoded: a session saved with a checkpoint holds them
    // without copying (tens of MB).
    std::shared_ptr<const std::vector<std::uint8_t>> depth_png, colour_png;
    KeyframeFootprint footprint;  // at fused_at (the Mapper's)
    double travelled = 0.0;       // viewpoint distance along the kept keyframes from the first
    double nearest = 0.0;         // sharedDistance() to the nearest other kept keyframe
    // On disk: the images are in the store's SpillFile (depth at disk_offset, colour after it),
    // depth_png and colour_png are empty.
    bool on_disk = false;
    std::shared_ptr<const SpillFile> disk;  // the file, kept open for whoever holds the entry
    std::uint64_t disk_offset = 0;
    std::size_t depth_bytes = 0, colour_bytes = 0;
    // The images (PNG), read back from disk when they are there; throw std::runtime_error, naming
    // the file's folder, when that fails.
    std::shared_ptr<const std::vector<std::uint8_t>> depthImage() const;
    std::shared_ptr<const std::vector<std::uint8_t>> colourImage() const;
    // The images' bytes in memory.
    std::size_t imageBytes() const {
      return (depth_png ? depth_png->size() : 0) + (colour_png ? colour_png->size() : 0);
    }
  };

  explicit KeyframeStore(std::size_t budget_bytes) : budget_bytes_(budget_bytes) {}

  // Keeps the frame's images (`fused_at`: the corrected pose it was fused at), then lets kept
  // keyframes go, or moves their images to disk, while over budget. Returns the indices let go,
  // each as it was when let go.
  std::vector<std::size_t> add(const Frame& frame, const Eigen::Isometry3d& fused_at);
  // The same for an entry encoded already (encode(), here or by another store).
  std::vector<std::size_t> add(Entry entry);
  // The frame's images as the store keeps them (not kept: see add()).
  Entry encode(const Frame& frame, const Eigen::Isometry3d& fused_at);
  // Takes in `earlier` (a saved session's kept keyframes, with their poses in this store's frame)
  // before the keyframes kept so far, then fits the budget as add() does.
  void adopt(std::vector<Entry> earlier);
  std::size_t size() const { return entries_.size(); }
  // The index of the entry with this id; size() when it was let go.
  std::size_t find(std::uint64_t id) const;
  Entry& operator[](std::size_t i) { return entries_[i]; }
  const Entry& operator[](std::size_t i) const { return entries_[i]; }
  // The stored images back into `frame` (depth in metres, colour BGR), with the entry's
  // timestamp, index, anchor and odometry pose; read from disk when they are there.
  void decode(std::size_t i, Frame& frame);
  // The same for an entry of another store (a saved session's: its images in memory).
  void decode(const Entry& entry, Frame& frame);
  // The kept keyframes as they are now (images in memory shared, not copied; those on disk read
  // by whoever writes them, depthImage()): what a session saves.
  std::vector<Entry> entries() const;
  // Kept keyframes whose images are on disk, and the bytes the disk holds for them.
  std::size_t onDisk() const { return on_disk_; }
  std::uint64_t diskBytes() const { return spill_->bytes(); }
  // How the images are stored (a session records them). Depth: a 16-bit PNG of K / depth
  // (inverse depth, as the Kinect measures it, in steps of 1 / K per metre): a step is
  // depth^2 / K, at most half the noise sigma (kinectDepthSigma) from 0.4 to 5 m, so the
  // rounding adds 2% to the noise's variance while a noisy image takes a third less room than in
  // TUM's 0.2 mm steps. 0 is no depth; nearer than K / 65535 (2 cm) is dropped. Colour: a PNG
  // at half size, BGR, keeping 6 bits of 8 (an error of 2 levels in 255, not to be seen; it
  // compresses 40% better).
  static constexpr double kInverseDepthUnits = 1300.0;
  static constexpr int kColourBitsDropped = 2;
  std::size_t memoryBytes() const;

 private:
  // Viewpoint distance, scaled up within one visit (see keyframe_store.cpp).
  static double sharedDistance(const Entry& a, const Entry& b);
  void findNearest(std::size_t i);
  std::vector<std::size_t> fitBudget();
  std::size_t mostRedundant() const;
  std::size_t oldestInMemory() const;
  std::size_t nearestInMemory() const;
  bool moveToDisk(std::size_t i);
  void letGo(std::size_t i);

  std::size_t budget_bytes_;
  std::vector<Entry> entries_;
  std::size_t bytes_ = 0;  // images in memory
  std::uint64_t next_id_ = 0;
  std::shared_ptr<SpillFile> spill_ = std::make_shared<SpillFile>();
  std::size_t on_disk_ = 0;
  bool disk_refused_ = false;
  PngEncoder encoder_;
  PngDecoder decoder_;
  cv::Mat units_, inverse_, half_;  // buffers
};

}  // namespace rgbdmap
