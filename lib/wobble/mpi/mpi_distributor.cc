#include "wobble/mpi/mpi_distributor.h"

// the C API only: Open MPI's mpi.h otherwise pulls in its deprecated C++ bindings
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "wobble/core/parallel.h"

namespace wobble::mpi {
namespace {

// From this many ranks on, rank 0 only deals: bench/mpi_scaling_model.py, fed with
// bench/mpi_bench's numbers, puts the crossover near 48 (below it rank 0's share of the
// trials is worth more than the dealing it delays; above it the dealing is the bottleneck).
constexpr int kDealerOnlyRanks = 48;

constexpr int kResultsTag = 7101;  // worker -> rank 0: finished items, and a request for more
constexpr int kAssignTag = 7102;   // rank 0 -> worker: [first, count); count 0: no more

void Check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

// Sleeps between polls, from 20 µs up to 1 ms: a rank that waits gives its core away.
class Backoff {
 public:
  void Wait() {
    std::this_thread::sleep_for(std::chrono::microseconds(pause_));
    pause_ = std::min(pause_ * 2, 1000);
  }
  void Reset() { pause_ = 20; }

 private:
  int pause_ = 20;
};

void WaitFor(MPI_Request* request) {
  Backoff backoff;
  for (int done = 0;;) {
    Check(MPI_Test(request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (done) return;
    backoff.Wait();
  }
}

// Bytes can exceed an int count: sent in pieces of at most 1 GiB.
constexpr size_t kPiece = size_t(1) << 30;

void BroadcastBytes(Bytes* bytes, int rank) {
  std::uint64_t size = bytes->size();
  MPI_Request request;
  Check(MPI_Ibcast(&size, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD, &request), "MPI_Ibcast");
  WaitFor(&request);
  if (rank != 0) bytes->resize(size);
  for (size_t at = 0; at < size; at += kPiece) {
    const int count = int(std::min(kPiece, size_t(size) - at));
    Check(MPI_Ibcast(bytes->data() + at, count, MPI_BYTE, 0, MPI_COMM_WORLD, &request), "MPI_Ibcast");
    WaitFor(&request);
  }
}

struct Outcome {
  bool failed = false;
  Bytes bytes;
};

Outcome RunItem(const std::function<Bytes(size_t)>& item, size_t i) {
  try {
    return {false, item(i)};
  } catch (const std::exception& e) {
    return {true, EncodeError(e)};
  }
}

}  // namespace

bool LaunchedByMpirun() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMI_SIZE") != nullptr ||
         std::getenv("PMIX_RANK") != nullptr;
}

MpiDistributor::MpiDistributor(int* argc, char*** argv) {
  int provided = 0;
  Check(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
  int local_ranks = 1;
  if (const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE")) local_ranks = std::max(1, std::atoi(local));
  threads_per_rank_ = std::max(1, ResolveThreads(0) / local_ranks);
  InstallDistributor(this);
}

MpiDistributor::~MpiDistributor() {
  InstallDistributor(nullptr);
  MPI_Finalize();
}

void MpiDistributor::Abort(int code) { MPI_Abort(MPI_COMM_WORLD, code); std::abort(); }

std::vector<Bytes> MpiDistributor::Map(size_t n, const MapOptions& options, const std::function<Bytes(size_t)>& item) {
  if (ranks_ == 1) return LocalDistributor().Map(n, options, item);
  MapOptions o = options;
  if (o.threads <= 0) o.threads = threads_per_rank_;
  std::vector<Bytes> results;
  if (rank_ == 0) {
    results = Deal(n, o, item);
  } else {
    Work(o, item);
  }
  // every result to every rank, so that the ranks go on alike
  Bytes all;
  if (rank_ == 0) {
    ByteWriter w;
    for (const Bytes& r : results) w.PutString(r);
    all = w.Take();
  }
  BroadcastBytes(&all, rank_);
  std::vector<Bytes> out;
  out.reserve(n);
  ByteReader in(all);
  for (size_t i = 0; i < n; ++i) out.push_back(in.GetString());
  // the lowest failing item's error, on every rank (a failed item's bytes start with 0xFF)
  for (const Bytes& b : out)
    if (!b.empty() && static_cast<unsigned char>(b[0]) == 0xFF) RethrowEncodedError(b.substr(1));
  for (Bytes& b : out) b.erase(0, 1);
  return out;
}

// Rank 0: deals chunks to the other ranks as they ask, and runs chunks itself on the other
// threads. Results are stored with a one-byte flag in front (0 ok, 0xFF an encoded error).
std::vector<Bytes> MpiDistributor::Deal(size_t n, const MapOptions& o, const std::function<Bytes(size_t)>& item) {
  std::vector<Bytes> results(n);
  std::mutex mutex;  // next, done and on_result
  size_t next = 0, done = 0;
  // guided self-scheduling: a chunk is a share of what is left, so the last ones are small
  auto take = [&](int threads, size_t* first, size_t* count) {
    std::lock_guard<std::mutex> lock(mutex);
    const size_t left = n - next;
    *count = std::min(left, std::max<size_t>(size_t(threads), left / (3 * size_t(ranks_))));
    *first = next;
    next += *count;
  };
  auto store = [&](size_t i, const Outcome& r) {
    std::lock_guard<std::mutex> lock(mutex);
    results[i] = std::string(1, r.failed ? char(0xFF) : char(0)) + r.bytes;
    ++done;
    if (!r.failed && o.on_result) o.on_result(i, r.bytes);
  };
  // rank 0's own share: every thread but this one, which answers the others
  std::thread own([&] {
    const int threads = std::max(1, o.threads - 1);
    while (ranks_ < kDealerOnlyRanks) {
      size_t first, count;
      take(threads, &first, &count);
      if (count == 0) return;
      ParallelFor(count, threads, [&](size_t k) { store(first + k, RunItem(item, first + k)); });
    }
  });
  int stopped = 0;
  Backoff backoff;
  Bytes buffer;
  while (stopped < ranks_ - 1) {
    int flag = 0;
    MPI_Status status;
    Check(MPI_Iprobe(MPI_ANY_SOURCE, kResultsTag, MPI_COMM_WORLD, &flag, &status), "MPI_Iprobe");
    if (!flag) {
      backoff.Wait();
      continue;
    }
    backoff.Reset();
    int size = 0;
    MPI_Get_count(&status, MPI_BYTE, &size);
    buffer.resize(size_t(size));
    Check(MPI_Recv(buffer.data(), size, MPI_BYTE, status.MPI_SOURCE, kResultsTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "MPI_Recv");
    ByteReader in(buffer);
    const auto count = in.Get<std::uint64_t>();
    const auto threads = in.Get<std::int32_t>();
    for (std::uint64_t k = 0; k < count; ++k) {
      const auto i = in.Get<std::uint64_t>();
      const bool failed = in.Get<std::uint8_t>() != 0;
      store(size_t(i), Outcome{failed, in.GetString()});
    }
    std::uint64_t assignment[2];
    size_t first, chunk;
    take(threads, &first, &chunk);
    assignment[0] = first;
    assignment[1] = chunk;
    if (chunk == 0) ++stopped;
    Check(MPI_Send(assignment, 2, MPI_UINT64_T, status.MPI_SOURCE, kAssignTag, MPI_COMM_WORLD), "MPI_Send");
  }
  own.join();
  if (done != n) throw std::logic_error("MpiDistributor: items were lost");
  return results;
}

// Any other rank: asks rank 0 for chunks, runs them on its threads, sends their results with
// the next request, until rank 0 says there are no more.
void MpiDistributor::Work(const MapOptions& o, const std::function<Bytes(size_t)>& item) {
  std::vector<std::pair<size_t, Outcome>> finished;
  for (;;) {
    ByteWriter w;
    w.Put<std::uint64_t>(finished.size()).Put<std::int32_t>(o.threads);
    for (const auto& [i, r] : finished) w.Put<std::uint64_t>(i).Put<std::uint8_t>(r.failed).PutString(r.bytes);
    const Bytes message = w.Take();
    MPI_Request request;
    Check(MPI_Isend(message.data(), int(message.size()), MPI_BYTE, 0, kResultsTag, MPI_COMM_WORLD, &request),
          "MPI_Isend");
    WaitFor(&request);
    std::uint64_t assignment[2];
    Check(MPI_Irecv(assignment, 2, MPI_UINT64_T, 0, kAssignTag, MPI_COMM_WORLD, &request), "MPI_Irecv");
    WaitFor(&request);
    if (assignment[1] == 0) return;
    const size_t first = assignment[0], count = assignment[1];
    finished.assign(count, {});
    ParallelFor(count, o.threads, [&](size_t k) { finished[k] = {first + k, RunItem(item, first + k)}; });
  }
}

}  // namespace wobble::mpi
