#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "rgbdmap/tracking/image_pyramid.hpp"
#include "rgbdmap/tracking/readout_motion.hpp"
#include "rgbdmap/tracking/tracking_options.hpp"

namespace rgbdmap {

// The pixels of a keyframe that take part in alignment, per pyramid level: each one's 3-D
// point in the keyframe's camera and its intensity.
struct AlignmentReference {
  using Points = std::vector<Eigen::Vector4f, Eigen::aligned_allocator<Eigen::Vector4f>>;
  struct Level {
    LevelCamera camera;
    Points points;  // x y z I
  };
  std::vector<Level> levels;
  int valid_pixels = 0;  // at the finest level, before subsampling: the overlap denominator
  // The keyframe's camera motion per second of readout when it was read (rotation vector, then
  // translation), for estimating the readout: its points move by this times the readout.
  ReadoutMotion readout_rate = ReadoutMotion::Zero();

  // Takes pixels with depth from levels finest..coarsest of `pyramid`. On the finest level,
  // pixels with an intensity gradient under min_gradient are taken every other row and column.
  // With a rolling shutter, each point is moved to where the camera was at mid-readout.
  void build(const ImagePyramid& pyramid, int finest, int coarsest, float min_gradient,
             const ReadoutMotion& readout = ReadoutMotion::Zero());
};

struct AlignmentResult {
  // Maps keyframe-camera points into the current camera (= current_pose^-1 * keyframe_pose).
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  double overlap = 0.0;          // fraction of the keyframe's pixels that landed in the frame
  double intensity_sigma = 0.0;  // robust std-dev of the intensity residual, finest level
  double min_information = 0.0;  // smallest eigenvalue of the normalised Hessian, finest level
  // The Gauss-Newton Hessian at the finest level divided by the pixels that landed: the
  // information one aligned pixel gives about `motion` ([translation, rotation], left
  // increments), what a pose graph weighs this alignment by.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  // With a readout rate set (DenseAligner::setReadoutRate): the Gauss-Newton step of the
  // readout time (s) at the final motion, and its information (the Hessian's Schur complement
  // after the motion), 0 when the motion leaves the readout unobservable.
  double readout_step = 0.0;
  double readout_information = 0.0;
  bool finite = false;
};

// Coarse-to-fine dense alignment of a frame to a keyframe (DVO, Kerl et al. 2013): minimises
// intensity and depth differences of the keyframe's pixels warped into the frame, with Huber
// weights on residuals normalised by their robust spread, by Gauss-Newton on SE(3) (left
// increments). On the finest level the intensity residuals lose their robust mean beyond a
// tolerance (tracking.brightness: the camera's exposure changed, not its pose). Forward
// compositional: the frame's gradients are sampled where each point lands, from the interleaved
// samples the pyramid precomputes, so one lookup per point and step.
class DenseAligner {
 public:
  // The warped keyframe points of one step, a column per quantity (so that the normal equations
  // run over them 8 at a time): residuals and their Jacobian rows with respect to a left
  // increment (translation, rotation) of the motion. A point without a depth residual has
  // has_z 0 and zeros in rz and jz. Columns are padded with zeros to a multiple of 8.
  struct Residuals {
    std::vector<float> ji[6], jz[6], ri, rz, has_z;
    // Derivatives of ri and rz with respect to the readout time, when it is estimated.
    std::vector<float> ai, az;
    std::vector<std::uint32_t> source;  // the reference point each row is of
    std::size_t size = 0;
    void reset(std::size_t capacity);  // size 0, room for `capacity` points
    void padToLanes();                 // zeros up to the next multiple of 8 (size unchanged)
    std::array<std::vector<float>*, 17> columns();  // every one of them
  };

  explicit DenseAligner(const TrackingOptions& options) : options_(options) {}
  AlignmentResult align(const AlignmentReference& reference, const ImagePyramid& current,
                        const Eigen::Isometry3d& guess);
  // The current frame's motion during its readout, for the alignments that follow.
  void setReadoutMotion(const ReadoutMotion& readout) { readout_ = readout; }
  // The current frame's camera motion per second of readout: when not zero, alignments also
  // measure the readout time (AlignmentResult::readout_step), from both the frame's rows and
  // the reference's (AlignmentReference::readout_rate).
  void setReadoutRate(const ReadoutMotion& rate) { readout_rate_ = rate; }

 private:
  TrackingOptions options_;
  // Kept from call to call: megabytes that, allocated afresh for every alignment, the kernel
  // zeroed page by page (half of a replay's page faults).
  Residuals residuals_;
  std::vector<float> abs_i_, abs_z_;
  ReadoutMotion readout_ = ReadoutMotion::Zero();
  ReadoutMotion readout_rate_ = ReadoutMotion::Zero();
};

}  // namespace rgbdmap
