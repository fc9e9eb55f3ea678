#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace rgbdmap::test {

using XWindow = unsigned long;  // an X11 Window id (Xlib's macros stay out of the tests)

// An X server of our own (Xvfb) for tests of windows, and what a user or a window manager does
// to a window: find it by title, press a key, click its close button, take a screenshot.
class XvfbServer {
 public:
  XvfbServer();  // starts Xvfb and points DISPLAY at it; ok() says whether it worked
  ~XvfbServer();
  XvfbServer(const XvfbServer&) = delete;
  XvfbServer& operator=(const XvfbServer&) = delete;

  bool ok() const { return display_ != nullptr; }
  const std::string& why() const { return why_; }

  // The top-level window whose title starts with `prefix`, or 0.
  XWindow findWindow(const std::string& prefix) const;
  void pressKey(XWindow window, char key) const;
  // What a window manager sends when the user clicks the close button.
  void closeWindow(XWindow window) const;
  // The window's pixels, BGR.
  cv::Mat screenshot(XWindow window) const;

 private:
  int pid_ = -1;
  std::string why_;
  void* display_ = nullptr;  // Display*
};

}  // namespace rgbdmap::test
