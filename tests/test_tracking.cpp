// The dense tracker (tracking.method=dense) frame by frame, every frame, as the live path calls
// it: accuracy on the real TUM frames and on synthetic rooms with exact poses, and what it does
// with bad input: blanked depth, a frozen image, frames cut out. A lost frame keeps a predicted
// pose and is not mapped; no mapped frame may get a bad pose; tracking comes back.
#include <gtest/gtest.h>

#include <deque>
#include <fstream>
#include <functional>
#include <iostream>

#include "rgbdmap/base/image_buffer_pool.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/eval/trajectory_evaluation.hpp"
#include "rgbdmap/tracking/dense_tracker.hpp"
#include "rgbdmap/tracking/pose_provider.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

struct Tracked {
  std::vector<Frame> frames;  // pose, has_pose and timestamp of every frame fed
  std::vector<TrackingState> states;
  std::vector<std::size_t> shown;  // which sequence image each frame showed
  double readout = 0;              // the dense tracker's readout at the end (s)
};

// The preset's configuration with dense odometry; `tune`, if given, changes the tracking options.
Config configFor(const std::string& folder,
                 const std::function<void(TrackingOptions&)>& tune = nullptr) {
  Config config;
  const std::string preset = TumSequence::presetForFolder(folder);
  config.loadPreset(preset.empty() ? "default" : preset);
  config.pose.source = "odometry";
  config.tracking.method = "dense";
  if (tune) tune(config.tracking);
  return config;
}

// Feeds the images listed in `order` (indices into the sequence) with the stamps of the
// positions they are fed at (order[i] shown at the time of image stamps[i]); `edit` may change
// a frame before tracking.
Tracked track(const std::string& folder, const std::vector<std::size_t>& order,
              const std::vector<std::size_t>& stamps,
              const std::function<void(std::size_t, Frame&)>& edit = nullptr,
              const std::function<void(TrackingOptions&)>& tune = nullptr) {
  const Config config = configFor(folder, tune);
  TumSequence sequence(folder);
  std::unique_ptr<PoseProvider> tracker =
      makePoseProvider(config.pose, config.tracking, config.camera, config.filter.min_depth,
                       config.filter.max_depth);
  Tracked out;
  Frame frame;
  std::string error;
  for (std::size_t i = 0; i < order.size(); ++i) {
    EXPECT_TRUE(sequence.load(order[i], frame, error)) << error;
    frame.timestamp = sequence[stamps[i]].rgb_time;
    frame.index = i;
    frame.has_pose = false;
    if (edit) edit(i, frame);
    tracker->estimate(frame);
    out.frames.push_back(frame);
    out.frames.back().depth = cv::Mat();  // keep poses, not images
    out.frames.back().color = cv::Mat();
    out.states.push_back(tracker->state());
    out.shown.push_back(order[i]);
  }
  if (const auto* dense = dynamic_cast<const DenseTracker*>(tracker.get()))
    out.readout = dense->readout();
  return out;
}

std::vector<std::size_t> range(std::size_t from, std::size_t to) {
  std::vector<std::size_t> v;
  for (std::size_t i = from; i < to; ++i) v.push_back(i);
  return v;
}

// ATE (Horn-aligned, as TUM) of every frame fed, lost ones with their predicted pose.
double ate(const std::string& folder, const Tracked& tracked) {
  Trajectory estimate;
  for (const Frame& f : tracked.frames) estimate.push_back({f.timestamp, f.pose});
  TumSequence sequence(folder);
  return absoluteTrajectoryError(estimate, sequence.groundtruth()).translation.rmse;
}

// Largest position error of a mapped frame against the ground truth of the image it showed,
// both relative to the first frame (the tracker's world frame).
double worstMappedError(const std::string& folder, const Tracked& tracked) {
  TumSequence sequence(folder);
  const Eigen::Isometry3d first = *sequence[tracked.shown.front()].pose;
  double worst = 0;
  for (std::size_t i = 0; i < tracked.frames.size(); ++i) {
    if (!tracked.frames[i].has_pose) continue;
    const Eigen::Isometry3d truth = first.inverse() * *sequence[tracked.shown[i]].pose;
    worst = std::max(worst, (truth.translation() - tracked.frames[i].pose.translation()).norm());
  }
  return worst;
}

int count(const Tracked& t, TrackingState s) {
  return static_cast<int>(std::count(t.states.begin(), t.states.end(), s));
}

using test::kRpy;
using test::kXyz;

TEST(Tracking, Fr1XyzEveryFrame) {
  const std::string folder = test::tumDir(kXyz);
  const std::size_t n = TumSequence(folder).size();
  const Tracked t = track(folder, range(0, n), range(0, n));
  const double e = ate(folder, t);
  std::cout << "fr1/xyz ATE " << e << " m\n";
  EXPECT_EQ(count(t, TrackingState::kLost), 0);
  EXPECT_LT(e, 0.012);  // target 1.0 cm; measured 0.49 cm (0.60 as a global shutter)
}

TEST(Tracking, Fr1RpyHead100EveryFrame) {
  const std::string folder = test::tumDir(kRpy);
  const std::size_t n = TumSequence(folder).size();
  const Tracked t = track(folder, range(0, n), range(0, n));
  const double e = ate(folder, t);
  std::cout << "fr1/rpy head100 ATE " << e << " m, lost " << count(t, TrackingState::kLost) << "\n";
  EXPECT_LT(e, 0.035);  // target 3.0 cm; measured 1.0 cm (OpenCV RgbdOdometry f2f 3.5 cm)
  EXPECT_LE(count(t, TrackingState::kLost), 5);
}

// Keeps the last two keyframes it was given, as the loop thread holds a few until it has seen them.
struct KeepingSink : KeyframeSink {
  std::deque<TrackedKeyframe> kept;
  std::size_t added = 0;
  void addKeyframe(TrackedKeyframe keyframe) override {
    kept.push_back(std::move(keyframe));
    if (kept.size() > 2) kept.pop_front();
    ++added;
  }
};

// A keyframe's images (the sink's copies, relocalisation's) come from buffers the tracker took
// when it was made: mapping fresh memory on a keyframe cost more than tracking the frame
// (docs/benchmarks.md). Over more keyframes than relocalisation keeps, none is allocated.
TEST(Tracking, KeyframesTakeNoNewImageMemory) {
  const std::string folder = test::tumDir(kRpy);
  const Config config = configFor(folder);
  TumSequence sequence(folder);
  KeepingSink sink;
  DenseTracker tracker(config.camera, config.tracking, static_cast<float>(config.filter.min_depth),
                       static_cast<float>(config.filter.max_depth), &sink);
  const std::size_t before = imageBufferPool().allocations();
  Frame frame;
  std::string error;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    ASSERT_TRUE(sequence.load(i, frame, error)) << error;
    frame.timestamp = sequence[i].rgb_time;
    tracker.estimate(frame);
  }
  std::cout << tracker.keyframes() << " keyframes\n";
  EXPECT_GT(tracker.keyframes(),
            static_cast<std::uint64_t>(config.tracking.relocalisation_keyframes) + 3);
  EXPECT_EQ(sink.added, tracker.keyframes());
  EXPECT_EQ(imageBufferPool().allocations(), before);
  for (const TrackedKeyframe& k : sink.kept) {  // and they are the pool's
    EXPECT_EQ(k.color.u->currAllocator, &imageBufferPool());
    EXPECT_EQ(k.depth.u->currAllocator, &imageBufferPool());
  }
}

// A synthetic sequence written by `rgbdmap synth` with extra options; returns its folder.
std::string synth(const std::string& dir, const std::string& options) {
  std::string output;
  EXPECT_EQ(test::run(test::binary() + " synth --out " + dir + " " + options, &output), 0)
      << output;
  return dir;
}

TEST(Tracking, SyntheticFastPan) {
  // A circle of the room in 3 s: 4 degrees per frame.
  const std::string folder = synth(test::freshDir() + "/pan", "--frames 30 --loop-seconds 3");
  const Tracked t = track(folder, range(0, 30), range(0, 30));
  const double e = ate(folder, t);
  std::cout << "fast pan ATE " << e << " m\n";
  EXPECT_EQ(count(t, TrackingState::kLost), 0);
  EXPECT_LT(e, 0.008);
}

TEST(Tracking, SyntheticDeepRoom) {
  // A room 10 m x 7 m: the far walls are up to 5 m from the camera (beyond filter.max_depth,
  // so depth there is missing, as on a real Kinect).
  const std::string dir = test::freshDir();
  std::ofstream(dir + "/scene.yaml") << "format: rgbdmap synthetic scene 1\n"
                                        "units: metres; world z up; colours RGB\n"
                                        "primitives:\n"
                                        "  - kind: room\n"
                                        "    name: hall\n"
                                        "    min: [-5, -3.5, 0]\n"
                                        "    max: [5, 3.5, 3]\n"
                                        "    texture:\n"
                                        "      pattern: checker\n"
                                        "      color_a: [225, 210, 180]\n"
                                        "      color_b: [90, 70, 60]\n"
                                        "      scale: 0.3\n"
                                        "      angle_deg: 0\n";
  const std::string folder = synth(dir + "/hall", "--frames 30 --scene " + dir + "/scene.yaml");
  const Tracked t = track(folder, range(0, 30), range(0, 30));
  const double e = ate(folder, t);
  std::cout << "deep room ATE " << e << " m\n";
  EXPECT_EQ(count(t, TrackingState::kLost), 0);
  EXPECT_LT(e, 0.008);
}

TEST(Tracking, BlankedDepthIsLostNotMappedAndRecovers) {
  const std::string folder = test::tumDir(kXyz);
  const std::size_t n = TumSequence(folder).size();
  const Tracked t = track(folder, range(0, n), range(0, n), [](std::size_t i, Frame& f) {
    if (i >= 10 && i < 14) f.depth.setTo(0);
  });
  for (std::size_t i = 10; i < 14; ++i) {
    EXPECT_EQ(t.states[i], TrackingState::kLost) << "frame " << i;
    EXPECT_FALSE(t.frames[i].has_pose) << "frame " << i;
  }
  EXPECT_EQ(t.states[14], TrackingState::kRelocalised);
  for (std::size_t i = 15; i < n; ++i) EXPECT_TRUE(t.frames[i].has_pose) << "frame " << i;
  EXPECT_LT(worstMappedError(folder, t), 0.03);
  EXPECT_LT(ate(folder, t), 0.015);  // lost frames count, with their predicted pose
}

TEST(Tracking, FrozenImageGivesNoBadPose) {
  // Frame 10's image comes 6 times (a stalled camera), then the stream goes on at frame 16.
  const std::string folder = test::tumDir(kXyz);
  const std::size_t n = TumSequence(folder).size();
  std::vector<std::size_t> order = range(0, 11);
  for (int i = 0; i < 5; ++i) order.push_back(10);
  for (std::size_t i = 16; i < n; ++i) order.push_back(i);
  const Tracked t = track(folder, order, range(0, n));
  EXPECT_LT(worstMappedError(folder, t), 0.03);
  EXPECT_TRUE(t.frames.back().has_pose);
  int mapped_after = 0;
  for (std::size_t i = 16; i < t.frames.size(); ++i) mapped_after += t.frames[i].has_pose;
  EXPECT_GE(mapped_after, static_cast<int>(t.frames.size()) - 16 - 3);
}

TEST(Tracking, JumpGivesNoBadPoseAndRecovers) {
  // 0.4 s of the rotating rpy sequence cut out: the camera turned ~20 degrees meanwhile.
  const std::string folder = test::tumDir(kRpy);
  std::vector<std::size_t> order = range(0, 40);
  for (std::size_t i = 52; i < 80; ++i) order.push_back(i);
  const Tracked t = track(folder, order, order);
  // The same frames uncut drift by a few cm on this fast rotation: the cut may add at most 2 cm.
  const Tracked uncut = track(folder, range(0, 80), range(0, 80));
  const double worst = worstMappedError(folder, t), worst_uncut = worstMappedError(folder, uncut);
  std::cout << "jump: lost " << count(t, TrackingState::kLost) << ", relocalised "
            << count(t, TrackingState::kRelocalised) << ", worst mapped error " << worst
            << " m (uncut " << worst_uncut << " m)\n";
  EXPECT_LT(worst, worst_uncut + 0.02);
  EXPECT_TRUE(t.frames.back().has_pose);
}

TEST(Tracking, ExposureChangesAreNotMotion) {
  // Frames 40-100 of fr1/rpy: the camera's auto-exposure swings by up to 30 grey levels against
  // the keyframes while it turns. Tracked frame by frame with the brightness offset and without.
  const std::string folder = test::tumDir(kRpy);
  const std::size_t n = TumSequence(folder).size();
  const double with = ate(folder, track(folder, range(40, n), range(40, n)));
  const double without = ate(folder, track(folder, range(40, n), range(40, n), nullptr,
                                           [](TrackingOptions& o) { o.brightness = "none"; }));
  std::cout << "fr1/rpy 40-100: ATE " << with << " m with the brightness offset, " << without
            << " m without\n";
  EXPECT_LT(with, without);
}

TEST(Tracking, SteepEdgesDoNotMisleadTheCoarseLevels) {
  // Every third frame of fr1/rpy, from frames 0 and 5: a camera turning three times as fast, so
  // that each frame starts pixels away from where it lands on the coarse levels. Weighing the
  // residuals of steep image edges down there (tracking.coarse_gradient_knee) keeps the
  // steps on the broad shapes; weighed alike, the edges drag some frames into a wrong minimum.
  const std::string folder = test::tumDir(kRpy);
  const std::size_t n = TumSequence(folder).size();
  double with = 0, without = 0;
  for (std::size_t from : {0, 5}) {
    std::vector<std::size_t> every3;
    for (std::size_t i = from; i < n; i += 3) every3.push_back(i);
    with += ate(folder, track(folder, every3, every3)) / 2;
    without += ate(folder, track(folder, every3, every3, nullptr,
                                 [](TrackingOptions& o) { o.coarse_gradient_knee = 0; })) /
               2;
  }
  std::cout << "fr1/rpy every third frame: mean ATE " << with << " m with the knee, " << without
            << " m without\n";
  EXPECT_LT(with, 0.025);  // measured 1.2 cm (without: 4.4 cm)
  EXPECT_LT(with, 0.6 * without);
}

}  // namespace
}  // namespace rgbdmap

namespace rgbdmap {
namespace {

TEST(Tracking, ARollingShutterIsUndoneOnFastTurns) {
  // fr1/rpy turns up to 1.5 rad/s: a Kinect's colour rows, read one after another, see the
  // scene a few pixels apart from top to bottom, differently in every frame. The preset's
  // camera.readout undoes the camera's motion over the readout row by row; as a global shutter
  // (readout 0) the frames are aligned by a pose that fits no row well.
  const std::string folder = test::tumDir(kRpy);
  const std::size_t n = TumSequence(folder).size();
  ASSERT_GT(configFor(folder).tracking.readout, 0.0) << "the tum_fr1 preset has no readout";
  double with = 0, without = 0;
  const std::vector<std::size_t> starts = {0, 15, 30};
  for (std::size_t from : starts) {
    const std::vector<std::size_t> frames = range(from, n);
    with += ate(folder, track(folder, frames, frames)) / starts.size();
    without += ate(folder, track(folder, frames, frames, nullptr,
                                 [](TrackingOptions& o) {
                                   o.readout = 0;
                                   o.estimate_readout = false;
                                 })) /
               starts.size();
  }
  std::cout << "fr1/rpy every frame from 0, 15, 30: mean ATE " << with
            << " m with the rolling shutter undone, " << without << " m without\n";
  EXPECT_LT(with, 0.015);  // measured 1.00 cm (without: 1.72 cm)
  EXPECT_LT(with, 0.8 * without);
}

TEST(Tracking, ASyntheticRollingShutterIsUndoneWithItsReadout) {
  // The fast pan's circle in 3 s (0.07 rad per frame) through a camera whose rows are read over
  // 20 ms, each rendered where the camera was when it was read: the exact truth of what
  // camera.readout models. Tracked as a global shutter, the pan is wrong by centimetres. (The
  // first keyframe, made before the camera's velocity is known, is replaced at the next frame.)
  const std::string folder =
      test::sharedSynthetic("rolling_pan_90", " --frames 90 --loop-seconds 3 --readout 0.02");
  const Tracked with = track(folder, range(0, 90), range(0, 90), nullptr,
                             [](TrackingOptions& o) { o.readout = 0.02; });
  const Tracked without = track(folder, range(0, 90), range(0, 90), nullptr,
                                [](TrackingOptions& o) { o.estimate_readout = false; });
  const double e_with = ate(folder, with), e_without = ate(folder, without);
  std::cout << "rolling-shutter pan ATE " << e_with << " m with its readout, " << e_without
            << " m as a global shutter\n";
  EXPECT_EQ(count(with, TrackingState::kLost), 0);
  EXPECT_LT(e_with, 0.35 * e_without);  // measured 0.47 cm against 2.91
  EXPECT_LT(e_with, 0.008);
}

TEST(Tracking, TrackingMeasuresARollingShuttersReadout) {
  // The same 20 ms pan through the default configuration, which knows of no rolling shutter
  // (camera.readout 0): every alignment of the turning camera measures how much longer a readout
  // fits better, and tracking goes on with their weighted mean.
  const std::string folder =
      test::sharedSynthetic("rolling_pan_90", " --frames 90 --loop-seconds 3 --readout 0.02");
  ASSERT_EQ(configFor(folder).tracking.readout, 0.0);
  const Tracked measured = track(folder, range(0, 90), range(0, 90));
  const Tracked global = track(folder, range(0, 90), range(0, 90), nullptr,
                               [](TrackingOptions& o) { o.estimate_readout = false; });
  const double e_measured = ate(folder, measured), e_global = ate(folder, global);
  std::cout << "rolling-shutter pan: readout measured " << measured.readout * 1e3
            << " ms (truth 20), ATE " << e_measured << " m, as a global shutter " << e_global
            << " m\n";
  EXPECT_NEAR(measured.readout, 0.02, 0.002);  // measured 19.9 ms
  EXPECT_LT(e_measured, 0.5 * e_global);       // measured 0.70 cm against 2.91
}

TEST(Tracking, AReadoutSetOnAGlobalShutterIsMeasuredAway) {
  // A global-shutter orbit tracked with a Kinect's 13.3 ms readout configured: undone with it,
  // the rows are moved where they never were. What tracking measures takes the readout back
  // towards zero, and most of the error with it.
  const std::string folder =
      test::sharedSynthetic("short_orbit", " --frames 130 --fps 10 --loop-seconds 10");
  const auto kinect = [](bool estimate) {
    return [estimate](TrackingOptions& o) {
      o.readout = 0.0133;
      o.estimate_readout = estimate;
    };
  };
  const Tracked measured = track(folder, range(0, 130), range(0, 130), nullptr, kinect(true));
  const Tracked fixed = track(folder, range(0, 130), range(0, 130), nullptr, kinect(false));
  const double e_measured = ate(folder, measured), e_fixed = ate(folder, fixed);
  std::cout << "global-shutter orbit with 13.3 ms configured: readout measured "
            << measured.readout * 1e3 << " ms, ATE " << e_measured << " m, kept " << e_fixed
            << " m\n";
  EXPECT_LT(measured.readout, 0.004);
  EXPECT_LT(e_measured, 0.6 * e_fixed);  // measured 0.57 cm against 1.41
}

}  // namespace
}  // namespace rgbdmap
