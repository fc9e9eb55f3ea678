#pragma once

#include <Eigen/Geometry>

#include "rgbdmap/base/binary_record.hpp"
#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/slam/place_recognition.hpp"
#include "rgbdmap/slam/pose_graph.hpp"

namespace rgbdmap {

// The pieces a session is written in, shared by its files (session_file) and its live stream
// (session_stream), so that both say a pose, an edge or a camera the same way. Every reader
// checks what it reads and fails naming the record ("corrupt (...)").

void putPose(RecordWriter& out, const Eigen::Isometry3d& pose);
Eigen::Isometry3d getPose(BinaryReader& in);

void putCamera(RecordWriter& out, const CameraIntrinsics& camera);
CameraIntrinsics getCamera(BinaryReader& in);

void putEdge(RecordWriter& out, const PoseGraph::Edge& edge);
// `keyframes`: how many keyframes the edge may join (ids beyond are corrupt).
PoseGraph::Edge getEdge(BinaryReader& in, std::size_t keyframes);

// A place's appearance: ORB descriptors with their 3-D points.
void putView(RecordWriter& out, const RelocalisationView& view);
RelocalisationView getView(BinaryReader& in);

}  // namespace rgbdmap
