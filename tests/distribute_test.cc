// core/distribute.h on one process (the MPI runner is checked by tests/cli/check_mpi.py under
// mpirun): results in item order whatever the threads, exact bytes, the lowest failing item's
// error class on the caller, and Maps nested in an item run on that item's thread.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <set>
#include <thread>

#include "wobble/core/distribute.h"
#include "wobble/core/errors.h"

namespace wobble {
namespace {

std::function<Bytes(size_t)> Squares() {
  return [](size_t i) { return ByteWriter().Put<double>(std::sqrt(double(i))).Put<std::uint64_t>(i * i).Take(); };
}

TEST(DistributedMap, ResultsInItemOrderWhateverTheThreads) {
  MapOptions one, four;
  one.threads = 1;
  four.threads = 4;
  const std::vector<Bytes> a = DistributedMap(1000, one, Squares());
  const std::vector<Bytes> b = DistributedMap(1000, four, Squares());
  ASSERT_EQ(a.size(), 1000u);
  EXPECT_EQ(a, b);
  for (size_t i = 0; i < a.size(); ++i) {
    ByteReader in(a[i]);
    EXPECT_EQ(in.Get<double>(), std::sqrt(double(i)));
    EXPECT_EQ(in.Get<std::uint64_t>(), i * i);
  }
  EXPECT_TRUE(DistributedMap(0, four, Squares()).empty());
}

TEST(DistributedMap, ReportsEveryResultOnceAsItArrives) {
  MapOptions o;
  o.threads = 3;
  std::multiset<size_t> seen;
  o.on_result = [&](size_t i, const Bytes& r) {
    seen.insert(i);
    EXPECT_EQ(r, Squares()(i));
  };
  DistributedMap(200, o, Squares());
  EXPECT_EQ(seen.size(), 200u);
  for (size_t i = 0; i < 200; ++i) EXPECT_EQ(seen.count(i), 1u);
}

TEST(DistributedMap, TheLowestFailingItemsErrorKeepsItsClass) {
  MapOptions o;
  o.threads = 4;
  auto failing = [](size_t i) -> Bytes {
    if (i == 37) throw NumericalStop("item 37 overflowed");
    if (i == 80) throw InputError("item 80 was bad");
    return "ok";
  };
  try {
    DistributedMap(100, o, failing);
    FAIL() << "no error";
  } catch (const NumericalStop& e) {
    EXPECT_STREQ(e.what(), "item 37 overflowed");
  }
  EXPECT_THROW(DistributedMap(100, o, [](size_t i) -> Bytes {
                 if (i == 3) throw LimitExceeded("too many");
                 return "";
               }),
               LimitExceeded);
  EXPECT_THROW(RethrowEncodedError(EncodeError(Interrupted("stop"))), Interrupted);
  EXPECT_THROW(RethrowEncodedError(EncodeError(std::invalid_argument("bad"))), InputError);
}

TEST(DistributedMap, AMapInsideAnItemRunsOnThatItemsThread) {
  MapOptions o;
  o.threads = 2;
  std::mutex mutex;
  bool nested_on_other_thread = false;
  const std::vector<Bytes> outer = DistributedMap(6, o, [&](size_t i) {
    const std::thread::id me = std::this_thread::get_id();
    MapOptions inner_options;
    inner_options.threads = 8;
    const std::vector<Bytes> inner = DistributedMap(5, inner_options, [&](size_t k) {
      if (std::this_thread::get_id() != me) {
        std::lock_guard<std::mutex> lock(mutex);
        nested_on_other_thread = true;
      }
      return std::to_string(i * 10 + k);
    });
    std::string joined;
    for (const Bytes& b : inner) joined += b + " ";
    return joined;
  });
  EXPECT_FALSE(nested_on_other_thread);
  EXPECT_EQ(outer[2], "20 21 22 23 24 ");
}

TEST(Bytes, DoublesAndStringsRoundTripBitForBit) {
  const std::vector<double> values{0.1, -0.0, std::numeric_limits<double>::denorm_min(),
                                   std::numeric_limits<double>::infinity(), 1e308, -3.0 / 7.0};
  const Bytes b = ByteWriter().PutDoubles(values).PutString("a,b\nc").Put<std::int32_t>(-5).Take();
  ByteReader in(b);
  const std::vector<double> back = in.GetDoubles();
  ASSERT_EQ(back.size(), values.size());
  for (size_t i = 0; i < values.size(); ++i) EXPECT_EQ(std::memcmp(&back[i], &values[i], sizeof(double)), 0);
  EXPECT_EQ(in.GetString(), "a,b\nc");
  EXPECT_EQ(in.Get<std::int32_t>(), -5);
  EXPECT_THROW(in.Get<double>(), std::logic_error);  // nothing left: a short result is an error
}

TEST(Distributor, WithoutMpiTheProcessIsRankZeroOfOne) {
  EXPECT_EQ(CurrentDistributor().rank(), 0);
  EXPECT_EQ(CurrentDistributor().ranks(), 1);
  EXPECT_TRUE(IsOutputRank());
}

}  // namespace
}  // namespace wobble
