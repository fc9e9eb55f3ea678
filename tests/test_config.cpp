#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <fstream>
#include <sstream>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/config/config.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, SetsKeysFromText) {
  Config c;
  c.set("map.voxel_size", "0.005", "--set");
  c.set("keyframe.every_n", "3", "--set");
  c.set("camera.undistort", "false", "--set");
  c.set("keyframe.policy", "both", "--set");
  EXPECT_DOUBLE_EQ(c.map.voxel_size, 0.005);
  EXPECT_EQ(c.keyframe.every_n, 3);
  EXPECT_FALSE(c.filter.undistort);
  EXPECT_FALSE(c.tracking.undistort);
  EXPECT_EQ(c.keyframe.policy, "both");
}

TEST(Config, RejectsUnknownKeysAndBadValuesNamingTheKey) {
  Config c;
  EXPECT_NE(messageOf([&] {
              c.set("map.voxelsize", "0.01", "--set");
            }).find("unknown config key 'map.voxelsize'"),
            std::string::npos);
  const std::string range = messageOf([&] { c.set("map.voxel_size", "-1", "--set"); });
  EXPECT_NE(range.find("map.voxel_size"), std::string::npos);
  EXPECT_NE(range.find("outside"), std::string::npos);
  EXPECT_NE(messageOf([&] { c.set("keyframe.every_n", "ten", "--set"); }).find("not an integer"),
            std::string::npos);
  EXPECT_NE(messageOf([&] { c.set("keyframe.every_n", "0", "--set"); }).find("keyframe.every_n"),
            std::string::npos);
  EXPECT_NE(messageOf([&] { c.set("pose.source", "magic", "--set"); }).find("not one of"),
            std::string::npos);
  EXPECT_NE(
      messageOf([&] { c.set("filter.min_depth", "9", "--set"); }).find("below filter.max_depth"),
      std::string::npos);
  EXPECT_DOUBLE_EQ(c.map.voxel_size, 0.01);  // a rejected value leaves the old one
}

TEST(Config, YamlErrorsNameFileAndLine) {
  const std::string dir = test::freshDir();
  const std::string path = dir + "/bad.yaml";
  std::ofstream(path) << "map:\n  voxel_size: 0.02\n  colour_mode: fancy\n";
  Config c;
  const std::string message = messageOf([&] { c.loadYaml(path); });
  EXPECT_NE(message.find(path + ":3"), std::string::npos) << message;
  EXPECT_NE(message.find("map.colour_mode"), std::string::npos) << message;

  std::ofstream(path) << "map: [unclosed\n";
  EXPECT_NE(messageOf([&] { c.loadYaml(path); }).find("invalid YAML"), std::string::npos);
  EXPECT_NE(messageOf([&] { c.loadYaml(dir + "/missing.yaml"); }).find("cannot open"),
            std::string::npos);
}

TEST(Config, PresetsLoadAndEffectiveConfigRoundTrips) {
  for (const char* preset :
       {"default", "tum_fr1", "tum_fr2", "tum_fr3", "kinect_v1", "xtion", "kinect_v1_raw"}) {
    Config c;
    EXPECT_NO_THROW(c.loadPreset(preset)) << preset;
  }
  // A camera whose depth is not registered to colour: its depth camera's own intrinsics.
  Config seven_scenes;
  seven_scenes.loadPreset("seven_scenes");
  EXPECT_FALSE(seven_scenes.camera.depthRegistered());
  EXPECT_DOUBLE_EQ(seven_scenes.camera.depth_fx, 585.0);
  EXPECT_DOUBLE_EQ(seven_scenes.camera.depth_scale, 1000.0);
  Config fr1;
  fr1.loadPreset("tum_fr1");
  EXPECT_DOUBLE_EQ(fr1.camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1.camera.k3, 1.1633);
  fr1.set("map.voxel_size", "0.004", "--set");
  const std::string dir = test::freshDir();
  std::ofstream(dir + "/effective.yaml") << fr1.toYaml();
  Config reloaded;
  reloaded.loadYaml(dir + "/effective.yaml");
  const auto original_keys = fr1.keys();
  const auto reloaded_keys = reloaded.keys();
  ASSERT_EQ(original_keys.size(), reloaded_keys.size());
  for (std::size_t i = 0; i < original_keys.size(); ++i)
    EXPECT_EQ(reloaded_keys[i].get(), original_keys[i].get()) << original_keys[i].name;
  EXPECT_DOUBLE_EQ(reloaded.map.voxel_size, 0.004);
  EXPECT_DOUBLE_EQ(reloaded.camera.cy, 255.3);
  EXPECT_NE(messageOf([] { Config().loadPreset("tum_fr9"); }).find("unknown preset"),
            std::string::npos);
}

// What spdlog logs while `f` runs.
std::string logOf(const std::function<void()>& f) {
  std::ostringstream lines;
  const std::shared_ptr<spdlog::logger> before = spdlog::default_logger();
  auto logger = std::make_shared<spdlog::logger>(
      "test", std::make_shared<spdlog::sinks::ostream_sink_mt>(lines));
  logger->set_pattern("%v");
  spdlog::set_default_logger(logger);
  f();
  spdlog::set_default_logger(before);
  return lines.str();
}

TEST(Config, OneKeyUndoesTheLensInTrackingAndFusion) {
  Config c;
  c.set("camera.undistort", "false", "--set");
  EXPECT_FALSE(c.tracking.undistort);
  EXPECT_FALSE(c.filter.undistort);
  c.set("camera.undistort", "true", "--set");
  EXPECT_TRUE(c.tracking.undistort);
  EXPECT_TRUE(c.filter.undistort);
  // Only the one key is listed and written; the former names are not.
  const std::string list = listKeys(c.keys(), false);
  EXPECT_NE(list.find("camera.undistort"), std::string::npos) << list;
  EXPECT_EQ(list.find("tracking.undistort"), std::string::npos) << list;
  EXPECT_EQ(list.find("filter.undistort"), std::string::npos) << list;
  EXPECT_EQ(test::countOccurrences(c.toYaml(), "  undistort: "), 1u) << c.toYaml();
}

TEST(Config, AConfigurationSavedWithTheFormerUndistortKeysLoadsWithOneWarning) {
  const std::string dir = test::freshDir();
  // MAP.yaml as runs wrote it before (and a session's config.yaml): both former keys.
  const std::string both = dir + "/MAP.yaml";
  std::ofstream(both) << "camera:\n  fx: 517.3\ntracking:\n  method: dense\n  undistort: false  "
                         "# dense: undo lens distortion\nfilter:\n  min_depth: 0.3\n  undistort: "
                         "false  # undo lens distortion when the camera has it\n";
  Config c;
  const std::string log = logOf([&] { c.loadYaml(both); });
  EXPECT_FALSE(c.tracking.undistort);
  EXPECT_FALSE(c.filter.undistort);
  EXPECT_DOUBLE_EQ(c.camera.fx, 517.3);
  EXPECT_EQ(test::countOccurrences(log, "\n"), 1u) << log;
  EXPECT_NE(log.find(both + ": tracking.undistort and filter.undistort are now camera.undistort"),
            std::string::npos)
      << log;
  // Either one alone sets the one key, and says so once.
  for (const std::string section : {"tracking", "filter"}) {
    const std::string one = dir + "/" + section + ".yaml";
    std::ofstream(one) << section << ":\n  undistort: false\n";
    Config d;
    const std::string said = logOf([&] { d.loadYaml(one); });
    EXPECT_FALSE(d.tracking.undistort) << section;
    EXPECT_FALSE(d.filter.undistort) << section;
    EXPECT_EQ(test::countOccurrences(said, "\n"), 1u) << said;
    EXPECT_NE(said.find(one + ": " + section + ".undistort is now camera.undistort"),
              std::string::npos)
        << said;
  }
  // A configuration written now has the one key and loads without a word.
  const std::string now = dir + "/now.yaml";
  std::ofstream(now) << c.toYaml();
  Config e;
  EXPECT_EQ(logOf([&] { e.loadYaml(now); }), "");
  EXPECT_FALSE(e.tracking.undistort);
  EXPECT_FALSE(e.filter.undistort);
}

}  // namespace
}  // namespace rgbdmap
