// Microbenchmarks of the per-keyframe path on a real TUM frame (fr1/rpy), stage by stage, with
// PNG decoding as the cost floor a replay pays anyway and PCL's statistical outlier removal
// (the original method's filter) for comparison. These measure; they assert nothing.
#include <benchmark/benchmark.h>
#include <pcl/filters/statistical_outlier_removal.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <memory>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/base/png_decoder.hpp"
#include "rgbdmap/base/run_stats.hpp"
#include "rgbdmap/capture/tum_sequence.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/mapping/back_projector.hpp"
#include "rgbdmap/mapping/depth_filter.hpp"
#include "rgbdmap/mapping/depth_smoother.hpp"
#include "rgbdmap/mapping/keyframe_integrator.hpp"
#include "rgbdmap/mapping/mesh_extractor.hpp"
#include "rgbdmap/mapping/tsdf_integrator.hpp"
#include "rgbdmap/mapping/voxel_map.hpp"
#include "rgbdmap/sessions/map_piece.hpp"
#include "rgbdmap/sim/building.hpp"
#include "rgbdmap/sim/camera_path.hpp"
#include "rgbdmap/sim/synthetic_sequence.hpp"
#include "rgbdmap/tracking/dense_tracker.hpp"
#include "rgbdmap/tracking/orb_matches.hpp"

namespace {

const std::string kSequence =
    std::string(RGBDMAP_DATA_DIR) + "/tum/rgbd_dataset_freiburg1_rpy_head100";
constexpr std::size_t kFrameIndex = 50;  // mid-sequence: a typical view of the scene
constexpr int kSceneEveryN = 10;         // the scene map: every 10th frame, as the default run

// Everything the benchmarks share, loaded once: the sequence, its fr1 configuration, one
// decoded frame, the frame's points as the integrator would fuse them, and a map of the scene.
struct Fixture {
  rgbdmap::Config config;
  std::unique_ptr<rgbdmap::TumSequence> sequence;
  rgbdmap::Frame frame;
  cv::Mat filtered_depth;      // after the depth filter and smoothing
  rgbdmap::PointBatch points;  // filtered_depth projected, as fused
  std::unique_ptr<rgbdmap::VoxelMap> scene;

  Fixture() {
    config.loadPreset(rgbdmap::TumSequence::presetForFolder(kSequence));
    rgbdmap::TumSequence::Options options;
    options.depth_scale = config.camera.depth_scale;
    sequence = std::make_unique<rgbdmap::TumSequence>(kSequence, options);
    load(kFrameIndex, frame);

    filtered_depth = frame.depth.clone();
    cv::Mat scratch;
    filter().apply(filtered_depth, scratch);
    rgbdmap::DepthSmoother::Buffers buffers;
    smoother().apply(filtered_depth, buffers);
    projector().project(filtered_depth, frame.color, frame.pose, points);

    scene = std::make_unique<rgbdmap::VoxelMap>(config.map.voxel_size);
    rgbdmap::KeyframeIntegrator integrator(config.camera, config.filter, config.map);
    rgbdmap::RunStats stats;
    rgbdmap::Frame keyframe;
    for (std::size_t i = 0; i < sequence->size(); i += kSceneEveryN) {
      if (!(*sequence)[i].pose) continue;
      load(i, keyframe);
      integrator.integrate(keyframe, *scene, stats);
    }
  }

  void load(std::size_t i, rgbdmap::Frame& out) {
    std::string error;
    if (!sequence->load(i, out, error)) throw std::runtime_error(error);
    if (!out.has_pose) throw std::runtime_error(out.origin + ": no ground-truth pose");
  }

  // The stages configured as KeyframeIntegrator configures them for this sequence.
  rgbdmap::DepthFilter filter() const { return rgbdmap::DepthFilter(config.filter); }
  rgbdmap::DepthSmoother smoother() const {
    rgbdmap::DepthSmoother s;
    s.radius = config.filter.smooth_radius;
    s.max_relative_range = config.filter.edge_jump;
    s.drop_unsmoothed = true;
    return s;
  }
  rgbdmap::BackProjector projector(bool subsample = true) const {
    rgbdmap::BackProjector p(config.camera, config.filter.undistort);
    const double f = std::min(config.camera.fx, config.camera.fy);
    if (subsample && config.filter.subsample)
      p.setSubsampleBelowDepth(static_cast<float>(config.map.voxel_size * f / 4.0));
    return p;
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

// The cost floor: reading and decoding one colour + depth PNG pair (and converting depth to
// metres), as the replay's capture thread does for every frame.
void BM_TumLoadPngPair(benchmark::State& state) {
  Fixture& f = fixture();
  rgbdmap::Frame frame;
  std::string error;
  for (auto _ : state) {
    if (!f.sequence->load(kFrameIndex, frame, error)) state.SkipWithError(error.c_str());
    benchmark::DoNotOptimize(frame.depth.data);
  }
}
BENCHMARK(BM_TumLoadPngPair)->Unit(benchmark::kMillisecond);

// Decoding alone, the same pair from memory into reused images: arg 0 cv::imdecode (libpng and
// zlib), arg 1 PngDecoder (libdeflate), which TumSequence uses for such PNGs.
void BM_PngDecodePair(benchmark::State& state) {
  Fixture& f = fixture();
  const auto read = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
  };
  const std::vector<std::uint8_t> color_png = read((*f.sequence)[kFrameIndex].rgb_path);
  const std::vector<std::uint8_t> depth_png = read((*f.sequence)[kFrameIndex].depth_path);
  const bool ours = state.range(0) != 0;
  rgbdmap::PngDecoder decoder;
  cv::Mat color, depth;
  std::string error;
  for (auto _ : state) {
    if (ours) {
      using Mode = rgbdmap::PngDecoder::Mode;
      if (decoder.decode(color_png.data(), color_png.size(), Mode::kColor, color, error) !=
              rgbdmap::PngDecoder::Status::kDecoded ||
          decoder.decode(depth_png.data(), depth_png.size(), Mode::kDepth, depth, error) !=
              rgbdmap::PngDecoder::Status::kDecoded)
        state.SkipWithError(("not decoded: " + error).c_str());
    } else {
      cv::imdecode(color_png, cv::IMREAD_COLOR, &color);
      cv::imdecode(depth_png, cv::IMREAD_UNCHANGED, &depth);
    }
    benchmark::DoNotOptimize(color.data);
    benchmark::DoNotOptimize(depth.data);
  }
  state.SetLabel(ours ? "PngDecoder" : "cv::imdecode");
}
BENCHMARK(BM_PngDecodePair)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Ratio-test matching of two real frames' ORB descriptors (800 features each), as loop closure
// compares a new keyframe with each remembered place near it: arg 0 OpenCV's brute-force Hamming
// knnMatch, arg 1 ratioMatches (tracking/orb_matches.hpp), which give the same matches.
void BM_OrbRatioMatches(benchmark::State& state) {
  Fixture& f = fixture();
  const auto describe = [&f](std::size_t index) {
    const cv::Mat image = cv::imread((*f.sequence)[index].rgb_path, cv::IMREAD_GRAYSCALE);
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    cv::ORB::create(800)->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
    return descriptors;
  };
  const cv::Mat a = describe(kFrameIndex), b = describe(kFrameIndex + 2);
  const bool ours = state.range(0) != 0;
  std::vector<cv::DMatch> matches;
  cv::BFMatcher opencv(cv::NORM_HAMMING);
  for (auto _ : state) {
    if (ours) {
      rgbdmap::ratioMatches(a, b, matches);
    } else {
      matches.clear();
      std::vector<std::vector<cv::DMatch>> knn;  // knnMatch appends to what it is given
      opencv.knnMatch(a, b, knn, 2);
      for (const auto& m : knn)
        if (m.size() == 2 && m[0].distance <= 0.8f * m[1].distance) matches.push_back(m[0]);
    }
    benchmark::DoNotOptimize(matches.data());
  }
  state.SetLabel(std::string(ours ? "ratioMatches" : "cv::BFMatcher") + ", " +
                 std::to_string(a.rows) + " x " + std::to_string(b.rows) + " descriptors, " +
                 std::to_string(matches.size()) + " matches");
}
BENCHMARK(BM_OrbRatioMatches)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Dense tracking of fr1/rpy's fastest turns (frames 40-70, decoded beforehand), a new tracker
// each iteration, with the fr1 preset: arg 0 its 13.3 ms readout kept, arg 1 the readout also
// measured (tracking.estimate_readout, the default). Time per iteration = 31 frames.
void BM_DenseTrackingFastTurns(benchmark::State& state) {
  Fixture& f = fixture();
  static const std::vector<rgbdmap::Frame> frames = [&f] {
    std::vector<rgbdmap::Frame> out(31);
    for (std::size_t i = 0; i < out.size(); ++i) f.load(40 + i, out[i]);
    return out;
  }();
  rgbdmap::TrackingOptions options = f.config.tracking;
  options.estimate_readout = state.range(0) != 0;
  rgbdmap::Frame frame;
  for (auto _ : state) {
    rgbdmap::DenseTracker tracker(f.config.camera, options,
                                  static_cast<float>(f.config.filter.min_depth),
                                  static_cast<float>(f.config.filter.max_depth));
    for (const rgbdmap::Frame& in : frames) {
      frame = in;
      frame.has_pose = false;
      tracker.estimate(frame);
    }
    benchmark::DoNotOptimize(frame.pose);
  }
  state.SetLabel(options.estimate_readout ? "readout measured" : "readout fixed");
}
BENCHMARK(BM_DenseTrackingFastTurns)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Range, flying-pixel and speck filtering of a 640x480 depth image. The filter works in place,
// so each iteration starts from a copy of the raw depth (a 1.2 MB memcpy, included).
void BM_DepthFilter(benchmark::State& state) {
  Fixture& f = fixture();
  const rgbdmap::DepthFilter filter = f.filter();
  cv::Mat depth, scratch;
  for (auto _ : state) {
    f.frame.depth.copyTo(depth);
    filter.apply(depth, scratch);
    benchmark::DoNotOptimize(depth.data);
  }
}
BENCHMARK(BM_DepthFilter)->Unit(benchmark::kMillisecond);

// A keyframe made into a map piece for a fleet's merger (4 x 4 blocks averaged, colour
// resized): what a streaming node spends on each keyframe (on its publisher thread).
void BM_MakeMapPiece(benchmark::State& state) {
  Fixture& f = fixture();
  rgbdmap::Frame piece;
  for (auto _ : state) {
    rgbdmap::makeMapPiece(f.frame, piece);
    benchmark::DoNotOptimize(piece.depth.data);
  }
}
BENCHMARK(BM_MakeMapPiece)->Unit(benchmark::kMillisecond);

// Edge-aware inverse-depth smoothing of the filtered image (copy included, as above).
void BM_DepthSmoother(benchmark::State& state) {
  Fixture& f = fixture();
  const rgbdmap::DepthSmoother smoother = f.smoother();
  cv::Mat depth;
  rgbdmap::DepthSmoother::Buffers buffers;
  for (auto _ : state) {
    f.filtered_depth.copyTo(depth);
    smoother.apply(depth, buffers);
    benchmark::DoNotOptimize(depth.data);
  }
}
BENCHMARK(BM_DepthSmoother)->Unit(benchmark::kMillisecond);

// Back-projection of the filtered frame into world points. Arg 1: with near-range subsampling
// as configured (what the integrator does); arg 0: every valid pixel.
void BM_BackProject(benchmark::State& state) {
  Fixture& f = fixture();
  const rgbdmap::BackProjector projector = f.projector(state.range(0) != 0);
  rgbdmap::PointBatch batch;
  for (auto _ : state) {
    batch.clear();
    projector.project(f.filtered_depth, f.frame.color, f.frame.pose, batch);
    benchmark::DoNotOptimize(batch.positions.data());
  }
  state.counters["points"] = static_cast<double>(batch.size());
}
BENCHMARK(BM_BackProject)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

rgbdmap::TsdfIntegrator tsdfFor(const rgbdmap::Config& config) {
  rgbdmap::TsdfIntegrator t;
  t.camera = config.camera;
  t.truncation = config.map.truncation;
  t.truncation_sigmas = config.map.truncation_sigmas;
  return t;
}

// Fusing one filtered frame along its lines of sight into an empty map: every block is new
// (the first keyframe).
// Argument: fusion threads.
void BM_TsdfIntegrateIntoEmptyMap(benchmark::State& state) {
  Fixture& f = fixture();
  rgbdmap::TsdfIntegrator tsdf = tsdfFor(f.config);
  rgbdmap::WorkerPool pool(static_cast<int>(state.range(0)));
  std::size_t blocks = 0;
  for (auto _ : state) {
    rgbdmap::VoxelMap map(f.config.map.voxel_size);
    tsdf.integrate(f.filtered_depth, f.frame.color, f.frame.pose, map, &pool);
    blocks = map.blockCount();
    benchmark::DoNotOptimize(blocks);
  }
  state.counters["blocks"] = static_cast<double>(blocks);
}
BENCHMARK(BM_TsdfIntegrateIntoEmptyMap)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The same into a map that already holds the scene (every 10th frame of the sequence): mostly
// updates of existing blocks. Argument: fusion threads.
void BM_TsdfIntegrateIntoSceneMap(benchmark::State& state) {
  Fixture& f = fixture();
  rgbdmap::TsdfIntegrator tsdf = tsdfFor(f.config);
  rgbdmap::WorkerPool pool(static_cast<int>(state.range(0)));
  rgbdmap::VoxelMap map = *f.scene;
  for (auto _ : state) {
    tsdf.integrate(f.filtered_depth, f.frame.color, f.frame.pose, map, &pool);
    benchmark::ClobberMemory();
  }
  state.counters["map_blocks"] = static_cast<double>(map.blockCount());
}
BENCHMARK(BM_TsdfIntegrateIntoSceneMap)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// A snapshot of the scene map as a point cloud (what a checkpoint writes), on the fusion side.
void BM_ExtractSnapshot(benchmark::State& state) {
  Fixture& f = fixture();
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  for (auto _ : state) {
    f.scene->extract(cloud);
    benchmark::DoNotOptimize(cloud.points.data());
  }
  state.counters["points"] = static_cast<double>(cloud.size());
}
BENCHMARK(BM_ExtractSnapshot)->Unit(benchmark::kMillisecond);

// The same map as a triangle mesh (--mesh): marching cubes over every block, on the fusion side.
void BM_ExtractMesh(benchmark::State& state) {
  Fixture& f = fixture();
  rgbdmap::TriangleMesh mesh;
  for (auto _ : state) {
    mesh = rgbdmap::extractMesh(*f.scene);
    benchmark::DoNotOptimize(mesh.triangles.data());
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size());
  state.counters["points"] = static_cast<double>(f.scene->pointCount());
}
BENCHMARK(BM_ExtractMesh)->Unit(benchmark::kMillisecond);

// The whole keyframe path (filter, smooth, project, fuse) into the scene map.
void BM_KeyframeIntegrate(benchmark::State& state) {
  Fixture& f = fixture();
  rgbdmap::KeyframeIntegrator integrator(f.config.camera, f.config.filter, f.config.map);
  rgbdmap::VoxelMap map = *f.scene;
  auto stats = std::make_unique<rgbdmap::RunStats>();
  for (auto _ : state) {
    integrator.integrate(f.frame, map, *stats);
    benchmark::ClobberMemory();
  }
  state.counters["map_blocks"] = static_cast<double>(map.blockCount());
}
BENCHMARK(BM_KeyframeIntegrate)->Unit(benchmark::kMillisecond);

// For comparison: PCL's k-d tree statistical outlier removal (mean-k 50, stddev 1.0), the
// original method's filter, on one frame's back-projected points (every valid pixel, as the
// original projects them; without the depth filter, which the original does not have).
void BM_PclStatisticalOutlierRemoval(benchmark::State& state) {
  Fixture& f = fixture();
  rgbdmap::BackProjector projector(f.config.camera, false);
  rgbdmap::PointBatch batch;
  projector.project(f.frame.depth, f.frame.color, f.frame.pose, batch);
  pcl::PointCloud<pcl::PointXYZRGB>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZRGB>);
  cloud->resize(batch.size());
  for (std::size_t i = 0; i < batch.size(); ++i) {
    (*cloud)[i].getVector3fMap() = batch.positions[i];
    (*cloud)[i].r = static_cast<std::uint8_t>(batch.colors[i].x());
    (*cloud)[i].g = static_cast<std::uint8_t>(batch.colors[i].y());
    (*cloud)[i].b = static_cast<std::uint8_t>(batch.colors[i].z());
  }
  pcl::PointCloud<pcl::PointXYZRGB> kept;
  for (auto _ : state) {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZRGB> sor;
    sor.setInputCloud(cloud);
    sor.setMeanK(50);
    sor.setStddevMulThresh(1.0);
    sor.filter(kept);
    benchmark::DoNotOptimize(kept.data());
  }
  state.counters["points"] = static_cast<double>(cloud->size());
  state.counters["kept"] = static_cast<double>(kept.size());
}
BENCHMARK(BM_PclStatisticalOutlierRemoval)->Unit(benchmark::kMillisecond);

// `rgbdmap synth`'s ray casting, one 640 x 480 frame: Arg 0 the 8 x 6 x 3 room seen from its
// walk, Arg 1 a 30 x 20 m office floor (a few hundred walls and pieces of furniture) seen from
// its tour, 100 s in, a room's door ahead. Second Arg: 1 through the ground grid (what synth
// does), 0 testing every primitive for every ray (what it did); single-threaded.
void BM_SyntheticRaycastFrame(benchmark::State& state) {
  const bool floor = state.range(0) == 1, grid = state.range(1) == 1;
  const rgbdmap::SyntheticScene scene =
      floor ? rgbdmap::generateBuilding(rgbdmap::BuildingOptions{})
            : rgbdmap::SyntheticScene::defaultRoom(Eigen::Vector3d(8.0, 6.0, 3.0));
  rgbdmap::SyntheticSequenceOptions options;
  options.path = floor ? "tour" : "walk";
  const Eigen::Isometry3d pose = rgbdmap::makeCameraPath(scene, options, 300.0)->pose(100.0);
  const rgbdmap::CameraIntrinsics camera;
  std::size_t hits = 0;
  for (auto _ : state) {
    hits = 0;
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const Eigen::Vector3d ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        double t = 0.0;
        Eigen::Vector3d normal;
        cv::Vec3b color;
        const Eigen::Vector3d direction = pose.linear() * ray;
        hits += grid ? scene.raycast(pose.translation(), direction, t, normal, color)
                     : scene.raycastEveryPrimitive(pose.translation(), direction, t, normal, color);
      }
    }
    benchmark::DoNotOptimize(hits);
  }
  state.counters["primitives"] = static_cast<double>(scene.primitives().size());
  state.counters["hits"] = static_cast<double>(hits);
}
BENCHMARK(BM_SyntheticRaycastFrame)
    ->Args({0, 1})
    ->Args({0, 0})
    ->Args({1, 1})
    ->Args({1, 0})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
