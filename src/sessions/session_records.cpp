#include "rgbdmap/sessions/session_records.hpp"

namespace rgbdmap {
namespace {

// A place's descriptors are ORB's: 32 bytes a row.
constexpr int kDescriptorBytes = 32;

}  // namespace

void putPose(RecordWriter& out, const Eigen::Isometry3d& pose) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) out.put<double>(pose.matrix()(r, c));
}

Eigen::Isometry3d getPose(BinaryReader& in) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = in.get<double>();
  // Bit for bit as written (a session read and written again is the same files); a rotation that
  // is not one is damage the checksum missed.
  if (!pose.matrix().allFinite() || !(pose.linear() * pose.linear().transpose()).isIdentity(1e-6))
    in.fail("corrupt (a pose that is not a rigid motion)");
  return pose;
}

void putCamera(RecordWriter& out, const CameraIntrinsics& c) {
  out.put<std::int32_t>(c.width);
  out.put<std::int32_t>(c.height);
  for (const double v : {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3}) out.put(v);
}

CameraIntrinsics getCamera(BinaryReader& in) {
  CameraIntrinsics c;
  c.width = in.get<std::int32_t>();
  c.height = in.get<std::int32_t>();
  for (double* v : {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2, &c.p1, &c.p2, &c.k3})
    *v = in.get<double>();
  if (c.width <= 0 || c.height <= 0 || !(c.fx > 0) || !(c.fy > 0))
    in.fail("corrupt (camera " + std::to_string(c.width) + "x" + std::to_string(c.height) + ")");
  return c;
}

void putEdge(RecordWriter& out, const PoseGraph::Edge& e) {
  out.put<std::int32_t>(e.from);
  out.put<std::int32_t>(e.to);
  out.put<std::uint8_t>(e.loop ? 1 : 0);
  putPose(out, e.measurement());
  const PoseGraph::Matrix6d sqrt_information = e.sqrtInformation();
  for (int i = 0; i < 36; ++i) out.put<double>(sqrt_information.data()[i]);
}

PoseGraph::Edge getEdge(BinaryReader& in, std::size_t keyframes) {
  PoseGraph::Edge e;
  e.from = in.get<std::int32_t>();
  e.to = in.get<std::int32_t>();
  e.loop = in.get<std::uint8_t>() != 0;
  e.setMeasurement(getPose(in));
  PoseGraph::Matrix6d sqrt_information;
  for (int i = 0; i < 36; ++i) sqrt_information.data()[i] = in.get<double>();
  if (!sqrt_information.allFinite()) in.fail("corrupt (an edge's weight is not a number)");
  e.setSqrtInformation(sqrt_information);
  if (e.from < 0 || e.to < 0 || static_cast<std::size_t>(e.from) >= keyframes ||
      static_cast<std::size_t>(e.to) >= keyframes)
    in.fail("corrupt (an edge " + std::to_string(e.from) + " -> " + std::to_string(e.to) +
            " between keyframes that are not there)");
  return e;
}

void putView(RecordWriter& out, const RelocalisationView& view) {
  out.put<std::uint64_t>(view.points.size());
  for (const cv::Point3f& p : view.points) out.put(p);
  const cv::Mat descriptors =
      view.descriptors.isContinuous() ? view.descriptors : view.descriptors.clone();
  out.put<std::uint64_t>(static_cast<std::uint64_t>(descriptors.rows));
  if (descriptors.rows > 0) out.putBytes(descriptors.data, descriptors.total());
}

RelocalisationView getView(BinaryReader& in) {
  RelocalisationView view;
  view.points.resize(in.count(sizeof(cv::Point3f)));
  for (cv::Point3f& p : view.points) p = in.get<cv::Point3f>();
  const std::size_t rows = in.count(kDescriptorBytes);
  if (rows != view.points.size())
    in.fail("corrupt (" + std::to_string(rows) + " descriptors for " +
            std::to_string(view.points.size()) + " points)");
  view.descriptors.create(static_cast<int>(rows), kDescriptorBytes, CV_8UC1);
  if (rows > 0) in.getBytes(view.descriptors.data, rows * kDescriptorBytes);
  view.described = true;
  return view;
}

}  // namespace rgbdmap
