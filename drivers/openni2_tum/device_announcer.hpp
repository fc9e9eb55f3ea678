#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

namespace rgbdmap::openni2_tum {

// Runs device connected/disconnected announcements on a thread of its own, each at its time.
// They cannot run on a device's playback thread: a host's listener may close the device in
// response, which joins that very thread.
class DeviceAnnouncer {
 public:
  using Clock = std::chrono::steady_clock;

  DeviceAnnouncer() = default;
  DeviceAnnouncer(const DeviceAnnouncer&) = delete;
  DeviceAnnouncer& operator=(const DeviceAnnouncer&) = delete;
  ~DeviceAnnouncer() { stop(); }

  // Runs `announce` at `when` (or at once if that has passed), after earlier ones.
  void schedule(Clock::time_point when, std::function<void()> announce);
  // Waits until every announcement due by `until` has run, giving up `slack` after `until`.
  // Returns at once on the announcer's own thread (a listener that closes a device in response).
  void finishDue(Clock::time_point until, Clock::duration slack);
  // Drops what is still pending and waits for a running announcement to finish.
  void stop();

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable changed_;
  std::multimap<Clock::time_point, std::function<void()>> pending_;
  bool stopping_ = false;
  bool announcing_ = false;  // an announcement runs outside the lock
  std::thread thread_;       // started with the first announcement
};

}  // namespace rgbdmap::openni2_tum
