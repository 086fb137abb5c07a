// Writes files on one worker thread while the caller renders the next frame (the machine
// has few cores; rendering and compression then overlap). Jobs run in submission order; the
// queue holds at most `max_pending` jobs, so Submit blocks when writing falls behind.
// A job that throws stops nothing else; the first error is rethrown by Wait() (and by
// Submit() after it happened), naming the file as the job's exception did.
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace wobble::pipelines {

class BackgroundWriter {
 public:
  explicit BackgroundWriter(int max_pending = 8);
  ~BackgroundWriter();  // waits for the queued jobs; errors not collected by Wait() are dropped
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

  // A job must own what it writes (copies, or smart pointers nobody else changes).
  void Submit(std::function<void()> job);
  // Blocks until every submitted job ran; rethrows the first error.
  void Wait();

 private:
  void Run();
  void RethrowLocked(std::unique_lock<std::mutex>& lock);

  const size_t max_pending_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::function<void()>> jobs_;
  bool busy_ = false, stop_ = false;
  std::exception_ptr error_;
  std::thread worker_;
};

}  // namespace wobble::pipelines
