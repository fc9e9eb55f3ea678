// Places matched with what they keep alone (a robot's stream carries no images): the same spot
// is found where the graph says it is, and views of other things are not matched.

#include <gtest/gtest.h>

#include "rgbdmap/sessions/session_file.hpp"
#include "rgbdmap/slam/motion.hpp"
#include "rgbdmap/slam/place_matcher.hpp"
#include "session_runs.hpp"
#include "test_support.hpp"

namespace rgbdmap {
namespace {

using test::rpySession;

// A place with every point (features and dense reference) moved by `motion`: the same spot seen
// from a camera at motion^-1.
std::shared_ptr<const PlaceRecognition::Place> moved(const PlaceRecognition::Place& place,
                                                     const Eigen::Isometry3f& motion) {
  auto out = std::make_shared<PlaceRecognition::Place>(place);
  for (cv::Point3f& p : out->view.points) {
    const Eigen::Vector3f q = motion * Eigen::Vector3f(p.x, p.y, p.z);
    p = cv::Point3f(q.x(), q.y(), q.z());
  }
  AlignmentReference reference;
  place.reference.expand(reference);
  for (auto& level : reference.levels)
    for (Eigen::Vector4f& p : level.points) p.head<3>() = motion * p.head<3>().eval();
  out->reference = PackedReference::pack(reference);
  return out;
}

TEST(PlaceMatcher, FindsWhereTheSameSpotWasSeenFrom) {
  const Session& s = rpySession();
  PlaceMatcher matcher(s.camera, TrackingOptions{}, LoopOptions{});
  Eigen::Isometry3f motion = Eigen::Isometry3f::Identity();
  motion.linear() =
      Eigen::AngleAxisf(0.05f, Eigen::Vector3f(0.3f, 1.0f, 0.2f).normalized()).toRotationMatrix();
  motion.translation() = Eigen::Vector3f(0.04f, -0.02f, 0.03f);
  int places = 0;
  for (const auto& place : s.graph.places) {
    if (!place) continue;
    ++places;
    // Itself: where it is.
    const auto self = matcher.match(*place, *place);
    ASSERT_TRUE(self);
    EXPECT_LT(self->later_in_earlier.translation().norm(), 0.001);
    EXPECT_LT(rotationAngle(self->later_in_earlier), 0.002);
    EXPECT_GT(self->overlap, 0.9);
    EXPECT_TRUE(self->information.allFinite());
    // Seen from elsewhere: that camera, within the packing's and the matcher's precision (the
    // moved place's view is drawn from its moved points, which fall between pixels: measured up
    // to 3.2 mm on these real frames).
    const auto found = matcher.match(*place, *moved(*place, motion));
    ASSERT_TRUE(found);
    const Eigen::Isometry3d error =
        motion.cast<double>() * found->later_in_earlier;  // later_in_earlier = motion^-1
    EXPECT_LT(error.translation().norm(), 0.004);
    EXPECT_LT(rotationAngle(error), 0.002);
  }
  EXPECT_GE(places, 3);
}

TEST(PlaceMatcher, ADifferentViewIsNotMatched) {
  const Session& s = rpySession();
  std::vector<std::size_t> ids;
  for (std::size_t id = 0; id < s.graph.places.size(); ++id)
    if (s.graph.places[id]) ids.push_back(id);
  ASSERT_GE(ids.size(), 2u);
  // The same place upside down and moved 3 m: its features no longer fit the other's geometry.
  auto moved = std::make_shared<PlaceRecognition::Place>(*s.graph.places[ids[0]]);
  for (cv::Point3f& p : moved->view.points) p = cv::Point3f(-p.x, -p.y, p.z + 3.0f);
  PlaceMatcher matcher(s.camera, TrackingOptions{}, LoopOptions{});
  EXPECT_FALSE(matcher.match(*s.graph.places[ids[0]], *moved));
  EXPECT_EQ(matcher.similarity(*s.graph.places[ids[0]], *moved),
            matcher.similarity(*s.graph.places[ids[0]], *s.graph.places[ids[0]]));
}

}  // namespace
}  // namespace rgbdmap
