#pragma once

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <opencv2/core.hpp>
#include <string>

#include "rgbdmap/base/frame.hpp"
#include "rgbdmap/config/config.hpp"

namespace rgbdmap {

// ROS images to the frame's conventions (colour BGR 8-bit, depth CV_32F metres with 0 for "no
// measurement"), written into reused buffers. Each returns false and says why in `error`
// (without the topic: the caller knows it) when the image cannot be converted.
//   colour: rgb8, bgr8
//   depth:  32FC1 metres (TUM's bags; NaN = no measurement), 16UC1 millimetres (openni2_camera,
//           freenect_camera; 0 = no measurement)
bool colorFromMessage(const sensor_msgs::Image& msg, cv::Mat& bgr, std::string& error);
bool depthFromMessage(const sensor_msgs::Image& msg, cv::Mat& metres, std::string& error);
// Whether an encoding is one the functions above take ("" = yes, else what is wrong).
std::string colorEncodingProblem(const std::string& encoding);
std::string depthEncodingProblem(const std::string& encoding);

CameraIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info);
// camera_info gives the intrinsics unless the user chose them: camera.intrinsics=device always
// takes camera_info; otherwise a named preset (--config, or the one a TUM-named bag implies) or
// camera.* keys changed from the default preset win.
bool intrinsicsFromCameraInfoWanted(const Config& config);

// Seconds since the epoch of a ROS stamp, as TUM's text files write them.
double stampSeconds(std::uint32_t sec, std::uint32_t nsec);

}  // namespace rgbdmap
