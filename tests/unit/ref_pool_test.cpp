// Unit tests of RefPool / PoolRef (server/session/ref_pool.h).
#include "server/session/ref_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "tests/support/allocation_counter.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::session {
namespace {

struct Payload {
  int value = 0;
  std::vector<int> buffer;
};

using Pool = RefPool<Payload>;
using Ref = PoolRef<Payload>;

Ref Make(Pool& pool, int value, Payload** out = nullptr) {
  Payload* p = nullptr;
  Ref ref = pool.Acquire(&p);
  p->value = value;
  if (out) *out = p;
  return ref;
}

// Whether the next Acquire hands back `address` (i.e. it is free and was the
// most recently returned); the acquired ref is released again.
bool NextAcquireIs(Pool& pool, const Payload* address) {
  Payload* p = nullptr;
  const Ref ref = pool.Acquire(&p);
  return p == address;
}

TEST(RefPoolTest, InitialObjectsAreMadeUpFront) {
  Pool pool(3);
  EXPECT_EQ(pool.size(), 3u);
  std::vector<Ref> refs;
  std::set<Payload*> distinct;
  for (int i = 0; i < 3; ++i) {
    Payload* p = nullptr;
    refs.push_back(pool.Acquire(&p));
    distinct.insert(p);
  }
  EXPECT_EQ(pool.size(), 3u);
  EXPECT_EQ(distinct.size(), 3u);
  // A fourth grows the pool.
  refs.push_back(Make(pool, 4));
  EXPECT_EQ(pool.size(), 4u);
}

TEST(RefPoolTest, DefaultRefIsEmpty) {
  Ref ref;
  EXPECT_FALSE(ref);
  ref.reset();  // harmless
  EXPECT_FALSE(ref);
  Ref copy = ref;
  EXPECT_FALSE(copy);
}

TEST(RefPoolTest, ReturnsOnLastRelease) {
  Pool pool;
  Payload* address = nullptr;
  Ref a = Make(pool, 7, &address);
  EXPECT_EQ(a->value, 7);
  EXPECT_EQ((*a).value, 7);
  EXPECT_EQ(&*a, address);
  Ref b = a;  // copy shares
  EXPECT_EQ(&*b, address);
  a.reset();
  EXPECT_FALSE(a);
  EXPECT_TRUE(b);
  // Still held by b: a new acquire gets a different object.
  EXPECT_FALSE(NextAcquireIs(pool, address));
  b.reset();
  EXPECT_TRUE(NextAcquireIs(pool, address));
  EXPECT_EQ(pool.size(), 2u);
}

TEST(RefPoolTest, CopyConstructionAndAssignmentShare) {
  Pool pool;
  Payload* first = nullptr;
  Payload* second = nullptr;
  Ref a = Make(pool, 1, &first);
  Ref b = Make(pool, 2, &second);
  {
    const Ref copy(a);
    EXPECT_EQ(&*copy, first);
  }
  EXPECT_TRUE(a);  // the copy's release did not return a's object
  EXPECT_FALSE(NextAcquireIs(pool, first));
  b = a;  // b drops `second` (its last ref) and shares `first`
  EXPECT_EQ(&*b, first);
  EXPECT_EQ(b->value, 1);
  EXPECT_TRUE(NextAcquireIs(pool, second));
  a.reset();
  EXPECT_FALSE(NextAcquireIs(pool, first));  // b still holds it
  b.reset();
  EXPECT_TRUE(NextAcquireIs(pool, first));
}

TEST(RefPoolTest, SelfAssignmentKeepsTheObject) {
  Pool pool;
  Payload* address = nullptr;
  Ref a = Make(pool, 3, &address);
  Ref& alias = a;
  a = alias;
  EXPECT_TRUE(a);
  EXPECT_EQ(&*a, address);
  EXPECT_FALSE(NextAcquireIs(pool, address));
  a.reset();
  EXPECT_TRUE(NextAcquireIs(pool, address));
}

TEST(RefPoolTest, MoveTransfersWithoutReturning) {
  Pool pool;
  Payload* address = nullptr;
  Ref a = Make(pool, 5, &address);
  Ref b(std::move(a));
  EXPECT_FALSE(a);  // NOLINT(bugprone-use-after-move): moved-from is empty
  EXPECT_EQ(&*b, address);
  EXPECT_FALSE(NextAcquireIs(pool, address));
  Ref c;
  c = std::move(b);
  EXPECT_FALSE(b);  // NOLINT(bugprone-use-after-move)
  EXPECT_EQ(&*c, address);
  EXPECT_FALSE(NextAcquireIs(pool, address));
  c.reset();
  EXPECT_TRUE(NextAcquireIs(pool, address));
  EXPECT_EQ(pool.size(), 2u);
}

TEST(RefPoolTest, MoveAssignOverAHeldRefReleasesIt) {
  Pool pool;
  Payload* first = nullptr;
  Payload* second = nullptr;
  Ref a = Make(pool, 1, &first);
  Ref b = Make(pool, 2, &second);
  b = std::move(a);
  EXPECT_EQ(&*b, first);
  EXPECT_TRUE(NextAcquireIs(pool, second));
}

TEST(RefPoolTest, ContentsSurviveReuse) {
  Pool pool;
  Payload* p = nullptr;
  {
    Ref ref = pool.Acquire(&p);
    p->buffer.assign(1000, 42);
  }
  Payload* again = nullptr;
  const Ref ref = pool.Acquire(&again);
  ASSERT_EQ(again, p);
  EXPECT_EQ(again->buffer.size(), 1000u);
  EXPECT_GE(again->buffer.capacity(), 1000u);
}

// A writer thread acquires and fills objects; a reader thread checks and
// releases them. Every object must come back to the pool (the pool's
// destructor aborts otherwise) and the pool stays small.
TEST(RefPoolTest, ReuseAcrossThreads) {
  Pool pool;
  constexpr int kItems = 20000;
  constexpr std::size_t kMaxInFlight = 4;
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<Ref> queue;
  bool bad_value = false;

  std::thread reader([&] {
    for (int expected = 0; expected < kItems; ++expected) {
      Ref ref;
      {
        std::unique_lock lock(mutex);
        changed.wait(lock, [&] { return !queue.empty(); });
        ref = std::move(queue.front());
        queue.pop_front();
      }
      changed.notify_all();
      // Read the payload the writer filled before handing it over.
      if (ref->value != expected || ref->buffer.size() != 16 || ref->buffer[15] != expected) bad_value = true;
      ref.reset();  // the last release, on the reader thread
    }
  });
  for (int i = 0; i < kItems; ++i) {
    Payload* p = nullptr;
    Ref ref = pool.Acquire(&p);
    p->value = i;
    p->buffer.assign(16, i);
    std::unique_lock lock(mutex);
    changed.wait(lock, [&] { return queue.size() < kMaxInFlight; });
    queue.push_back(std::move(ref));
    lock.unlock();
    changed.notify_all();
  }
  reader.join();
  EXPECT_FALSE(bad_value);
  EXPECT_TRUE(queue.empty());
  // In flight: up to kMaxInFlight queued, one held by the reader, one being
  // filled by the writer.
  EXPECT_LE(pool.size(), kMaxInFlight + 2);
}

// Many threads sharing one ref: copies and releases race on the count, and
// exactly one of them returns the object.
TEST(RefPoolTest, SharedAcrossThreadsReturnsExactlyOnce) {
  Pool pool;
  for (int round = 0; round < 200; ++round) {
    Payload* address = nullptr;
    Ref shared = Make(pool, round, &address);
    std::vector<std::thread> threads;
    std::atomic<int> sum{0};
    for (int t = 0; t < 4; ++t) {
      threads.emplace_back([copy = shared, &sum]() mutable {
        for (int i = 0; i < 50; ++i) {
          Ref inner = copy;
          sum += inner->value >= 0 ? 1 : 0;
        }
        copy.reset();
      });
    }
    shared.reset();
    for (auto& thread : threads) thread.join();
    EXPECT_EQ(sum.load(), 200);
    ASSERT_TRUE(NextAcquireIs(pool, address)) << "round " << round;
    ASSERT_EQ(pool.size(), 1u) << "round " << round;
  }
}

// Trim frees what a burst left once a trim has seen the burst end: the
// objects beyond the most in use since the previous trim, plus a spare.
TEST(RefPoolTest, TrimFreesWhatABurstLeft) {
  Pool pool;
  {
    std::vector<Ref> burst;
    for (int i = 0; i < 40; ++i) burst.push_back(Make(pool, i));
    EXPECT_EQ(pool.TrimNow(2), 0u) << "all in use";
  }
  ASSERT_EQ(pool.size(), 40u);
  // The burst is within this trim's window: kept, in case it comes again.
  EXPECT_EQ(pool.TrimNow(2), 0u);
  EXPECT_EQ(pool.size(), 40u);
  // A whole window without it: freed down to the spare.
  EXPECT_EQ(pool.TrimNow(2), 38u);
  EXPECT_EQ(pool.size(), 2u);
  // Those left still work, and the pool grows again on demand.
  std::vector<Ref> again;
  for (int i = 0; i < 5; ++i) again.push_back(Make(pool, i));
  EXPECT_EQ(pool.size(), 5u);
}

TEST(RefPoolTest, TrimNeverFreesObjectsInUse) {
  Pool pool;
  std::vector<Ref> held;
  for (int i = 0; i < 6; ++i) held.push_back(Make(pool, i));
  held.erase(held.begin() + 3, held.end());  // 3 held, 3 free
  pool.TrimNow(0);
  pool.TrimNow(0);
  EXPECT_EQ(pool.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(held[static_cast<std::size_t>(i)]->value, i);
  held.clear();
  pool.TrimNow(0);
  EXPECT_EQ(pool.size(), 3u) << "in use within this window";
  pool.TrimNow(0);
  EXPECT_EQ(pool.size(), 0u);
}

TEST(RefPoolTest, TrimWaitsForItsPeriod) {
  Pool pool;
  { std::vector<Ref> burst{Make(pool, 1), Make(pool, 2), Make(pool, 3)}; }
  pool.TrimNow(0);  // sees the burst
  EXPECT_EQ(pool.Trim(0, std::chrono::hours(1)), 3u) << "the first Trim runs at once";
  { std::vector<Ref> burst{Make(pool, 1), Make(pool, 2), Make(pool, 3)}; }
  EXPECT_EQ(pool.Trim(0, std::chrono::hours(1)), 0u) << "within the period";
  EXPECT_EQ(pool.size(), 3u);
}

// A steady state (the same number in use frame after frame) with a trim per
// frame allocates nothing: objects in steady use are never freed.
TEST(RefPoolTest, SteadyStateWithTrimsAllocatesNothing) {
  Pool pool;
  const auto frame = [&] {
    std::vector<Ref> refs;
    refs.reserve(8);
    Payload* p = nullptr;
    for (int i = 0; i < 6; ++i) refs.push_back(pool.Acquire(&p));
    refs.clear();
    pool.TrimNow(1);
  };
  for (int i = 0; i < 3; ++i) frame();  // warm
  std::vector<Ref> refs;
  refs.reserve(8);
  const std::size_t allocations = ::sim4cv::testing::AllocationsIn([&] {
    for (int round = 0; round < 100; ++round) {
      Payload* p = nullptr;
      for (int i = 0; i < 6; ++i) refs.push_back(pool.Acquire(&p));
      refs.clear();
      pool.TrimNow(1);
    }
  });
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(pool.size(), 6u);
}

}  // namespace
}  // namespace sim4cv::session
