// `rgbdmap record`: saves what a source delivers (a live OpenNI2 camera, an .oni recording or a
// TUM folder) as a TUM RGB-D folder, so captures can be replayed with --source tum:DIR and shared.
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/image_file.hpp"
#include "rgbdmap/capture/accelerometer_log.hpp"
#include "rgbdmap/config/config.hpp"
#include "rgbdmap/drivers/kinect_accelerometer.hpp"
#include "rgbdmap/runtime/run_signals.hpp"
#include "rgbdmap/runtime/source_factory.hpp"
#include "rgbdmap/tools/commands.hpp"
#include "rgbdmap/tools/fakenect_dump.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

constexpr double kTumDepthUnitsPerMetre = 5000.0;  // TUM's 16-bit depth PNGs

struct RecordOptions {
  std::string source;
  std::string out;
  std::uint64_t frames = 0;  // 0: until the source ends or Ctrl-C
  std::string config_file;
  std::vector<std::string> sets;
  std::string format = "tum";  // or "fakenect"
};

// One TUM list (rgb.txt or depth.txt), each line flushed as soon as its image is complete, so an
// interrupted recording still has lists that match its images.
class TumList {
 public:
  TumList(const std::string& path, const std::string& what, const std::string& origin,
          const std::string& columns = "timestamp filename")
      : path_(path), out_(path) {
    out_ << "# " << what << "\n# file: '" << origin << "'\n# " << columns << "\n";
    check();
  }
  void add(const std::string& stamp, const std::string& fields) {
    out_ << stamp << ' ' << fields << '\n';
    out_.flush();
    check();
  }

 private:
  void check() {
    if (!out_) throw InputError(path_ + ": cannot write (" + std::strerror(errno) + ")");
  }
  std::string path_;
  std::ofstream out_;
};

// Every image is written to one temporary file in the recording's folder and renamed into place,
// so no half-written PNG is ever listed, and a second Ctrl-C knows which file to remove.
fs::path partialImageIn(const fs::path& out) { return out / ".partial.png"; }

void writePng(const cv::Mat& image, const fs::path& partial, const fs::path& path) {
  std::string error;
  bool ok = false;
  try {
    ok = writeImageFile(partial.string(), image, error, 1);  // lossless; fast enough for live
  } catch (const cv::Exception&) {
    ok = false;
  }
  std::error_code ec;
  if (ok) fs::rename(partial, path, ec);
  if (!ok || ec) {
    fs::remove(partial, ec);
    throw InputError(path.string() + ": cannot write the image (disk full or read-only?)");
  }
}

// Metres to TUM depth units (5000 per metre, 0 = missing). Returns how many measurements were
// beyond the 16-bit range (13.1 m) and had to be dropped.
std::uint64_t toTumDepth(const cv::Mat& metres, cv::Mat& units) {
  units.create(metres.rows, metres.cols, CV_16UC1);
  std::uint64_t too_far = 0;
  for (int y = 0; y < metres.rows; ++y) {
    const float* in = metres.ptr<float>(y);
    std::uint16_t* out = units.ptr<std::uint16_t>(y);
    for (int x = 0; x < metres.cols; ++x) {
      const double value = std::round(static_cast<double>(in[x]) * kTumDepthUnitsPerMetre);
      if (!(value > 0)) {
        out[x] = 0;  // missing, negative or NaN
      } else if (value > 65535.0) {
        out[x] = 0;
        ++too_far;
      } else {
        out[x] = static_cast<std::uint16_t>(value);
      }
    }
  }
  return too_far;
}

// A source as a fakenect dump: every frame the source gives, until it ends or Ctrl-C.
int recordFakenect(const RecordOptions& o, const Config& config, const RunControl& control) {
  FakenectDump dump(o.out);
  std::unique_ptr<FrameSource> source = openSource(o.source, config);
  const std::string origin = source->describe();
  spdlog::info("recording {} into {} as a fakenect dump", origin, o.out);
  Frame frame;
  while (!control.stop.load() && (o.frames == 0 || dump.frames() < o.frames)) {
    const ReadStatus status = source->read(frame);
    if (status == ReadStatus::kEnd) break;
    if (status == ReadStatus::kSkipped) continue;
    if (status == ReadStatus::kTimeout)
      throw InputError(origin + ": camera stopped delivering frames (" +
                       std::to_string(dump.frames()) + " frames saved)");
    dump.add(frame);
  }
  std::printf(
      "recorded %llu frames to %s as a fakenect dump\n"
      "replay: FAKENECT_PATH=%s LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/fakenect "
      "rgbdmap --source openni2\n",
      static_cast<unsigned long long>(dump.frames()), o.out.c_str(),
      fs::absolute(o.out).string().c_str());
  return 0;
}

// A TUM folder being recorded from `origin`: its image lists, the accelerometer log (from the
// first frame that knows its up) and what was saved.
class TumRecording {
 public:
  TumRecording(const fs::path& out, const std::string& origin)
      : out_(out),
        origin_(origin),
        rgb_list_((out / "rgb.txt").string(), "color images", origin),
        depth_list_((out / "depth.txt").string(), "depth maps", origin) {}

  // Saves `frame`; not when its stamp is not after the last one's (said).
  void add(const Frame& frame) {
    // TUM file names are the stamps; a repeated or backwards stamp would clash or mis-sort.
    char stamp[64];
    std::snprintf(stamp, sizeof stamp, "%.6f", frame.timestamp);
    const double rounded_stamp = std::strtod(stamp, nullptr);
    if (written_ > 0 && rounded_stamp <= last_stamp_) {
      ++out_of_order_;
      spdlog::warn("{}: frame at {} s is not after the previous one ({} s); not recorded", origin_,
                   stamp, last_stamp_);
      return;
    }
    last_stamp_ = rounded_stamp;
    const std::string rgb_file = std::string("rgb/") + stamp + ".png";
    const std::string depth_file = std::string("depth/") + stamp + ".png";
    writePng(frame.color, partialImageIn(out_), out_ / rgb_file);
    too_far_ += toTumDepth(frame.depth, depth_units_);
    writePng(depth_units_, partialImageIn(out_), out_ / depth_file);
    rgb_list_.add(stamp, rgb_file);
    depth_list_.add(stamp, depth_file);
    if (frame.has_up) {
      if (!accelerometer_)
        accelerometer_.emplace((out_ / "accelerometer.txt").string(), "accelerometer data", origin_,
                               "timestamp ax ay az");
      // At rest, as TUM's: the reaction to gravity (1 g) in the Kinect accelerometer's axes.
      const Eigen::Vector3d a =
          AccelerometerLog::upInCamera(frame.up.normalized()) * KinectAcceleration::kGravity;
      char fields[96];
      std::snprintf(fields, sizeof fields, "%.6f %.6f %.6f", a.x(), a.y(), a.z());
      accelerometer_->add(stamp, fields);
    }
    ++written_;
  }

  // What was recorded, and how to replay it with the camera's intrinsics (a TUM folder holds
  // none).
  void report(const FrameSource& source) const {
    if (too_far_ > 0)
      spdlog::warn(
          "{} depth measurements beyond 13.1 m (the 16-bit TUM range) were saved as missing",
          too_far_);
    const CameraIntrinsics camera = source.intrinsics();
    std::printf("recorded %llu frames to %s (%llu skipped by the source, %llu out of order)\n",
                static_cast<unsigned long long>(written_), out_.string().c_str(),
                static_cast<unsigned long long>(source.skipped()),
                static_cast<unsigned long long>(out_of_order_));
    std::printf(
        "replay: rgbdmap --source tum:%s --set camera.fx=%g --set camera.fy=%g "
        "--set camera.cx=%g --set camera.cy=%g",
        fs::absolute(out_).string().c_str(), camera.fx, camera.fy, camera.cx, camera.cy);
    if (camera.hasDistortion())
      std::printf(
          " --set camera.k1=%g --set camera.k2=%g --set camera.p1=%g --set camera.p2=%g "
          "--set camera.k3=%g",
          camera.k1, camera.k2, camera.p1, camera.p2, camera.k3);
    std::printf("\n");
  }

  std::uint64_t written() const { return written_; }

 private:
  fs::path out_;
  std::string origin_;
  TumList rgb_list_, depth_list_;
  std::optional<TumList> accelerometer_;
  cv::Mat depth_units_;
  std::uint64_t written_ = 0, too_far_ = 0, out_of_order_ = 0;
  double last_stamp_ = 0;
};

// A source as a TUM folder: every frame the source gives, until it ends or Ctrl-C; a camera that
// stops delivering is waited for when it can reconnect.
int recordTum(const RecordOptions& o, const Config& config, const RunControl& control) {
  const fs::path out(o.out);
  std::error_code ec;
  if (fs::exists(out / "rgb.txt", ec) || fs::exists(out / "depth.txt", ec))
    throw InputError(o.out +
                     ": already holds a recording (rgb.txt/depth.txt); choose another --out");
  fs::create_directories(out / "rgb", ec);
  if (!ec) fs::create_directories(out / "depth", ec);
  if (ec) throw InputError(o.out + ": cannot create the folder (" + ec.message() + ")");

  std::unique_ptr<FrameSource> source = openSource(o.source, config);
  const std::string origin = source->describe();
  spdlog::info("recording {} into {}", origin, o.out);
  TumRecording recording(out, origin);
  Frame frame;
  while (!control.stop.load() && (o.frames == 0 || recording.written() < o.frames)) {
    const ReadStatus status = source->read(frame);
    if (status == ReadStatus::kEnd) break;
    if (status == ReadStatus::kSkipped) continue;
    if (status == ReadStatus::kTimeout) {
      if (!source->canReconnect()) throw InputError(origin + ": camera stopped delivering frames");
      spdlog::warn(
          "{}: camera stopped delivering frames; waiting for it (Ctrl-C stops, keeping "
          "the {} frames saved)",
          origin, recording.written());
      while (!control.stop.load() && !source->reconnect()) {
      }
      continue;
    }
    recording.add(frame);
  }
  recording.report(*source);
  return 0;
}

int record(const RecordOptions& o) {
  RunControl control;
  RunSignals signals(control);  // before the source starts any thread, so they inherit the mask
  // A recording saves every frame as it goes: no checkpoint to take, and a stop ends it after the
  // frame in hand.
  RunSignals::Run run;
  if (o.format == "tum") run.temporary_files = {partialImageIn(o.out).string()};
  run.checkpoints = false;
  run.stopping = "stopping after this frame";
  run.quitting = "quitting now (the lists hold every saved frame)";
  signals.runStarts(run);
  Config config;
  config.loadPreset(o.config_file.empty() ? presetForSource(o.source) : o.config_file);
  config.set("replay.rate", "0", "record");  // recordings and folders: every frame, lossless
  config.setAll(o.sets, "--set");
  return o.format == "fakenect" ? recordFakenect(o, config, control)
                                : recordTum(o, config, control);
}

}  // namespace

void addRecordCommand(CLI::App& app, Command& selected) {
  auto* cmd = app.add_subcommand(
      "record", "save a source (OpenNI2 camera, .oni file, TUM folder) as a TUM RGB-D folder");
  auto o = std::make_shared<RecordOptions>();
  cmd->add_option("-s,--source", o->source, "openni2 | openni2:URI | openni2:FILE.oni | tum:DIR")
      ->required();
  cmd->add_option("-o,--out", o->out, "folder to write rgb/, depth/, rgb.txt, depth.txt into")
      ->required();
  cmd->add_option("-n,--frames", o->frames, "stop after this many frames (default: all / Ctrl-C)");
  cmd->add_option("-c,--config", o->config_file, "YAML config: a preset name or a file");
  cmd->add_option("--set", o->sets, "override a config key (repeatable)");
  cmd->add_option("--format", o->format,
                  "tum (a TUM RGB-D folder) or fakenect (a dump libfreenect's fakenect plays as a "
                  "Kinect v1)")
      ->check(CLI::IsMember({"tum", "fakenect"}));
  cmd->callback([o, &selected] { selected = [o] { return record(*o); }; });
}

}  // namespace rgbdmap
