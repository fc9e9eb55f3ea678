#include "device_announcer.hpp"

#include <utility>

namespace rgbdmap::openni2_tum {

void DeviceAnnouncer::schedule(Clock::time_point when, std::function<void()> announce) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stopping_) return;
  pending_.emplace(when, std::move(announce));
  if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
  changed_.notify_all();
}

void DeviceAnnouncer::finishDue(Clock::time_point until, Clock::duration slack) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (std::this_thread::get_id() == thread_.get_id()) return;
  changed_.wait_until(lock, until + slack, [this, until] {
    return stopping_ || (!announcing_ && (pending_.empty() || pending_.begin()->first > until));
  });
}

void DeviceAnnouncer::stop() {
  std::thread thread;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    pending_.clear();
    thread = std::move(thread_);
    changed_.notify_all();
  }
  if (thread.joinable()) thread.join();
}

void DeviceAnnouncer::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_) {
    if (pending_.empty()) {
      changed_.wait(lock);
      continue;
    }
    const Clock::time_point due = pending_.begin()->first;
    if (Clock::now() < due) {
      changed_.wait_until(lock, due);
      continue;
    }
    std::function<void()> announce = std::move(pending_.begin()->second);
    pending_.erase(pending_.begin());
    // The host's listeners run inside; they may open or close devices, which can schedule more.
    announcing_ = true;
    lock.unlock();
    announce();
    lock.lock();
    announcing_ = false;
    changed_.notify_all();  // finishDue() may wait for this one
  }
}

}  // namespace rgbdmap::openni2_tum
