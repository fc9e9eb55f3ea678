#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace rgbdmap {

// A fixed set of threads that run one loop body over task indices [0, count) and return when
// every task is done; the calling thread takes tasks too. Tasks are handed out by an atomic
// counter, so which thread runs a task varies, but a body whose tasks write disjoint data gives
// the same result whatever the thread count (fusion writes each block from one task only).
// Nothing is allocated per run, so it can serve every keyframe.
class WorkerPool {
 public:
  // `threads`: threads that run tasks, the caller's included (1: the caller alone, no thread).
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  // Calls body(i) for every i in [0, count). The first exception a task throws is rethrown here
  // once every task has finished or been skipped.
  template <typename Body>
  void run(std::size_t count, Body& body) {
    runTasks(
        count, [](void* context, std::size_t i) { (*static_cast<Body*>(context))(i); }, &body);
  }

  // Threads to use for `requested` (0: every core the machine has).
  static int resolve(int requested);

 private:
  using Trampoline = void (*)(void*, std::size_t);
  void runTasks(std::size_t count, Trampoline call, void* context);
  void work();  // the task loop shared by the workers and the caller
  void workerMain();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  std::uint64_t generation_ = 0;  // bumped per run; workers wait for a new one
  bool stop_ = false;
  int active_ = 0;  // workers inside the current run
  std::size_t count_ = 0;
  Trampoline call_ = nullptr;
  void* context_ = nullptr;
  std::atomic<std::size_t> next_{0};
  std::exception_ptr error_;
  // The caller's: workers run its tasks no sooner than it would (a fusion thread that gives way
  // to tracking gives way with its workers).
  int niceness_ = 0;
};

// Calls body(i) for every i in [0, count): on the pool when there is one, else in turn on the
// calling thread.
template <typename Body>
void runTasks(WorkerPool* pool, std::size_t count, Body&& body) {
  if (pool)
    pool->run(count, body);
  else
    for (std::size_t i = 0; i < count; ++i) body(i);
}

}  // namespace rgbdmap
