#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <thread>

#include "rgbdmap/viewer/viewer_mailbox.hpp"

namespace rgbdmap {

struct ViewerOptions {
  std::string title = "rgbdmap";
  std::string caption;  // shown first in the status bar (e.g. the map file's name)
  int width = 1280;
  int height = 720;
  std::size_t max_points = 2'000'000;  // drawn at most; bigger maps are decimated
  double refresh_hz = 30.0;
  int nice = 10;       // the viewer thread's niceness: mapping comes first when the CPU is short
  bool follow = true;  // the view follows the camera (key f toggles)
  std::function<void()> on_snapshot;  // key s
  std::function<void()> on_stop;      // key q, or the window was closed
};

// One window with the growing map, the camera frustum and trajectory, the newest colour and
// depth images and a status bar, drawn by its own thread from what arrives in its mailbox.
// Keys: s snapshot, q quit, f follow/free view, c colour by height / RGB.
// Construct only when displayAvailable(): the window opens at once.
class Viewer {
 public:
  explicit Viewer(ViewerOptions options);
  ~Viewer();  // closes the window
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  // What the pipeline publishes to.
  ViewerMailbox& mailbox() { return mailbox_; }
  // Closes the window (if still open) and waits for the viewer thread.
  void close();
  // Waits until the user closes the window (q or the window's close button).
  void waitUntilClosed();

 private:
  void run();

  ViewerOptions options_;
  ViewerMailbox mailbox_;
  std::atomic<bool> close_requested_{false};
  std::thread thread_;
};

}  // namespace rgbdmap
