#include "wobble/core/distribute.h"

#include <atomic>
#include <mutex>

#include "wobble/core/errors.h"
#include "wobble/core/parallel.h"

namespace wobble {
namespace {

// Set on a thread while it runs an item: a Map called from inside one runs there, serially
// (a sweep case's trials stay on the thread the case got; the cases fill the cores).
thread_local bool inside_item = false;

struct InsideItem {
  bool before = inside_item;
  InsideItem() { inside_item = true; }
  ~InsideItem() { inside_item = before; }
};

std::atomic<Distributor*> installed{nullptr};

enum ErrorCode : std::uint8_t { kOther = 0, kInput = 1, kLimit = 2, kNumerical = 3, kInterrupted = 4 };

class Local final : public Distributor {
 public:
  std::vector<Bytes> Map(size_t n, const MapOptions& o, const std::function<Bytes(size_t)>& item) override {
    std::vector<Bytes> results(n);
    std::vector<Bytes> errors(n);
    std::vector<char> failed(n, 0);
    std::mutex report;
    ParallelFor(n, inside_item ? 1 : o.threads, [&](size_t i) {
      InsideItem guard;
      try {
        results[i] = item(i);
      } catch (const std::exception& e) {
        failed[i] = 1;
        errors[i] = EncodeError(e);
        return;
      }
      if (o.on_result) {
        std::lock_guard<std::mutex> lock(report);
        o.on_result(i, results[i]);
      }
    });
    for (size_t i = 0; i < n; ++i)
      if (failed[i]) RethrowEncodedError(errors[i]);
    return results;
  }
};

}  // namespace

Distributor& LocalDistributor() {
  static Local local;
  return local;
}

Distributor& CurrentDistributor() {
  Distributor* d = installed.load();
  return d ? *d : LocalDistributor();
}

void InstallDistributor(Distributor* distributor) { installed.store(distributor); }

std::vector<Bytes> DistributedMap(size_t n, const MapOptions& options, const std::function<Bytes(size_t)>& item) {
  if (inside_item) return LocalDistributor().Map(n, options, item);
  return CurrentDistributor().Map(n, options, [&](size_t i) {
    InsideItem guard;
    return item(i);
  });
}

Bytes EncodeError(const std::exception& e) {
  ErrorCode code = kOther;
  if (dynamic_cast<const LimitExceeded*>(&e)) code = kLimit;
  else if (dynamic_cast<const std::invalid_argument*>(&e)) code = kInput;
  else if (dynamic_cast<const NumericalStop*>(&e)) code = kNumerical;
  else if (dynamic_cast<const Interrupted*>(&e)) code = kInterrupted;
  return ByteWriter().Put<std::uint8_t>(code).PutString(e.what()).Take();
}

void RethrowEncodedError(const Bytes& encoded) {
  ByteReader in(encoded);
  const auto code = in.Get<std::uint8_t>();
  const std::string message = in.GetString();
  switch (code) {
    case kInput: throw InputError(message);
    case kLimit: throw LimitExceeded(message);
    case kNumerical: throw NumericalStop(message);
    case kInterrupted: throw Interrupted(message);
    default: throw std::runtime_error(message);
  }
}

}  // namespace wobble
