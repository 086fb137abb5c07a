// Independent work items spread over this process' threads and, when the app installed a
// distributed runner (lib/wobble/mpi, `mpirun -np N wobble ...`), over MPI ranks too: synthesis
// trials (annealing batches, CMA-ES generations, restarts), the condition map's rows, the
// sweep's cases.
//
// SPMD: under MPI every rank runs the same command and reaches the same DistributedMap calls in
// the same order; each call hands its items out dynamically (rank 0 deals them in chunks as
// ranks ask) and returns every item's result, in item order, on every rank, so the ranks go on
// identically. An item's result depends on its index alone, so 1 process, N threads and N ranks
// give the same results bit for bit (results cross as bytes, doubles copied exactly).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace wobble {

using Bytes = std::string;

struct MapOptions {
  int threads = 0;  // threads per process (0: every core)
  // On rank 0 only, as each item's result arrives (completion order, under a lock): the
  // sweep streams its finished rows to disk here.
  std::function<void(size_t index, const Bytes& result)> on_result;
};

class Distributor {
 public:
  virtual ~Distributor() = default;
  // item(i) for every i in [0, n), somewhere; every result in order, on every rank. An item
  // that throws: the lowest such index' error is rethrown on every rank (InputError,
  // LimitExceeded, NumericalStop and Interrupted keep their class; others become runtime_error).
  virtual std::vector<Bytes> Map(size_t n, const MapOptions& options, const std::function<Bytes(size_t)>& item) = 0;
  virtual int rank() const { return 0; }
  virtual int ranks() const { return 1; }
};

// The threads of this process only (core/parallel.h's ParallelFor).
Distributor& LocalDistributor();
// What DistributedMap uses: the installed one (MPI), else the local one. Map calls nested in a
// distributed item (a sweep case's annealing) run on the calling thread alone.
Distributor& CurrentDistributor();
// The app installs the MPI runner once, before any work; nullptr goes back to the local one.
void InstallDistributor(Distributor* distributor);
// Whether this process writes outputs and prints results: rank 0, or no MPI.
inline bool IsOutputRank() { return CurrentDistributor().rank() == 0; }

std::vector<Bytes> DistributedMap(size_t n, const MapOptions& options, const std::function<Bytes(size_t)>& item);

// An exception as bytes and back (the class by a code, then the message), so that an item's
// failure on another rank is rethrown as the same class.
Bytes EncodeError(const std::exception& e);
[[noreturn]] void RethrowEncodedError(const Bytes& encoded);

// Plain values to bytes and back, exactly (doubles by their bits).
class ByteWriter {
 public:
  template <class T> ByteWriter& Put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&v), sizeof v);
    return *this;
  }
  ByteWriter& PutString(const std::string& s) {
    Put<std::uint64_t>(s.size());
    bytes_ += s;
    return *this;
  }
  ByteWriter& PutDoubles(const std::vector<double>& v) {
    Put<std::uint64_t>(v.size());
    if (!v.empty()) bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
    return *this;
  }
  Bytes Take() { return std::move(bytes_); }

 private:
  Bytes bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(const Bytes& bytes) : bytes_(bytes) {}
  template <class T> T Get() {
    static_assert(std::is_trivially_copyable_v<T>);
    Need(sizeof(T));
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  std::string GetString() {
    const auto n = Get<std::uint64_t>();
    Need(n);
    std::string s = bytes_.substr(at_, n);
    at_ += n;
    return s;
  }
  std::vector<double> GetDoubles() {
    const auto n = Get<std::uint64_t>();
    if (n > (bytes_.size() - at_) / sizeof(double)) Need(bytes_.size() + 1);
    std::vector<double> v(n);
    if (n) std::memcpy(v.data(), bytes_.data() + at_, n * sizeof(double));
    at_ += n * sizeof(double);
    return v;
  }

 private:
  void Need(size_t n) const {
    if (n > bytes_.size() - at_) throw std::logic_error("ByteReader: a result is shorter than its reader expects");
  }
  const Bytes& bytes_;
  size_t at_ = 0;
};

}  // namespace wobble
