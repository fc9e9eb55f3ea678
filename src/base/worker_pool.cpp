#include "rgbdmap/base/worker_pool.hpp"

#include <algorithm>

#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/base/thread_priority.hpp"

namespace rgbdmap {

WorkerPool::WorkerPool(int threads) {
  for (int i = 1; i < std::max(1, threads); ++i) workers_.emplace_back([this] { workerMain(); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (std::thread& t : workers_) t.join();
}

int WorkerPool::resolve(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

void WorkerPool::work() {
  for (std::size_t i = next_.fetch_add(1); i < count_; i = next_.fetch_add(1)) {
    try {
      call_(context_, i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
      next_.store(count_);  // skip the tasks not started
    }
  }
}

void WorkerPool::workerMain() {
  nameThisThread("rgbdmap-worker");
  std::uint64_t seen = 0;
  int niceness = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      ++active_;
      niceness = niceness_;
    }
    stepBackFromTracking(niceness);
    work();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --active_;
    }
    done_.notify_one();
  }
}

void WorkerPool::runTasks(std::size_t count, Trampoline call, void* context) {
  if (count == 0) return;
  {
    // A worker that woke too late for the last run may still be leaving it: its reads of the
    // run's fields must end before they change.
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return active_ == 0; });
    count_ = count;
    call_ = call;
    context_ = context;
    error_ = nullptr;
    niceness_ = threadNiceness();
    next_.store(0);
    ++generation_;
  }
  if (!workers_.empty() && count > 1) start_.notify_all();
  work();
  std::exception_ptr error;
  {
    // Every task has been taken; wait for the workers still running one (a worker that wakes
    // only now finds none left and leaves at once).
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return active_ == 0; });
    error = error_;
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace rgbdmap
