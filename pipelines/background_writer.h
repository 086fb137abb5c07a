// Writes files on worker threads while the caller renders the next frame: compressing PNG
// and EXR frames costs more than rendering them, so writing is spread over `threads` workers
// (default: one per core). Jobs start in submission order and must write different files;
// the queue holds at most `max_pending` jobs, so Submit blocks when writing falls behind.
// A job that throws stops nothing else; the first error is rethrown by Wait() (and by
// Submit() after it happened), naming the file as the job's exception did.
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace wobble::pipelines {

class BackgroundWriter {
 public:
  explicit BackgroundWriter(int threads = 0, int max_pending = 16);  // threads 0: one per core
  ~BackgroundWriter();  // waits for the queued jobs; errors not collected by Wait() are dropped
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

  // A job must own what it writes (copies) and must not touch VTK objects, not even to
  // release one: VTK's garbage collector is not thread-safe (a job that dropped the last
  // reference to a vtkPolyData crashed in vtkGarbageCollector::Collect under ASan).
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
  int busy_ = 0;  // jobs running now
  bool stop_ = false;
  std::exception_ptr error_;
  std::vector<std::thread> workers_;
};

}  // namespace wobble::pipelines
