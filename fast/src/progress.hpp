#pragma once
// Progress of a multi-threaded loop, reported through an optional callback
// (the CLI prints it on a terminal). Calls are serialised; `done` counts
// finished work items over all threads.
#include <atomic>
#include <functional>
#include <mutex>

namespace fdsid {

class ProgressCounter {
 public:
  ProgressCounter(const std::function<void(int, int)>& callback, int total) : callback_(callback), total_(total) {}
  void add(int items = 1) {
    const int d = done_ += items;
    if (callback_) {
      std::lock_guard<std::mutex> lock(mu_);
      callback_(d, total_);
    }
  }

 private:
  const std::function<void(int, int)>& callback_;
  const int total_;
  std::atomic<int> done_{0};
  std::mutex mu_;
};

}  // namespace fdsid
