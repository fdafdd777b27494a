// A set of reusable objects handed out with an intrusive reference count, so
// the hot path publishes a frame to many readers without a heap allocation:
// the sim thread fills a pooled object, readers share it read-only, and the
// last release returns it to the pool. The set grows on demand and Trim gives
// back what a burst left: objects idle for a whole trim period.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "server/common/check.h"

namespace sim4cv::session {

template <typename T>
class RefPool;

template <typename T>
class PoolRef {
 public:
  PoolRef() = default;
  PoolRef(const PoolRef& other) : slot_(other.slot_) { Retain(); }
  PoolRef(PoolRef&& other) noexcept : slot_(other.slot_) { other.slot_ = nullptr; }
  PoolRef& operator=(PoolRef other) noexcept {
    std::swap(slot_, other.slot_);
    return *this;
  }
  ~PoolRef() { Release(); }

  const T& operator*() const { return slot_->value; }
  const T* operator->() const { return &slot_->value; }
  explicit operator bool() const { return slot_ != nullptr; }
  void reset() {
    Release();
    slot_ = nullptr;
  }

 private:
  friend class RefPool<T>;
  struct Slot {
    T value;
    std::atomic<int> refs{0};
    RefPool<T>* pool = nullptr;
  };
  explicit PoolRef(Slot* slot) : slot_(slot) { Retain(); }
  void Retain() {
    if (slot_) slot_->refs.fetch_add(1, std::memory_order_relaxed);
  }
  void Release() {
    if (slot_ && slot_->refs.fetch_sub(1, std::memory_order_acq_rel) == 1) slot_->pool->Return(slot_);
  }
  Slot* slot_ = nullptr;
};

template <typename T>
class RefPool {
 public:
  using Ref = PoolRef<T>;

  // Grows on demand; `initial` objects are made up front.
  explicit RefPool(std::size_t initial = 0) {
    for (std::size_t i = 0; i < initial; ++i) free_.push_back(MakeSlot());
  }
  RefPool(const RefPool&) = delete;
  RefPool& operator=(const RefPool&) = delete;
  ~RefPool() { SIM4CV_DEMAND(free_.size() == slots_.size()); }  // every Ref released

  // A free object (contents as its last user left them, so buffers keep their
  // capacity) for exclusive writing through `writable`, then sharing.
  Ref Acquire(T** writable) {
    typename Ref::Slot* slot = nullptr;
    {
      std::lock_guard lock(mutex_);
      if (free_.empty()) free_.push_back(MakeSlot());
      slot = free_.back();
      free_.pop_back();
      peak_in_use_ = std::max(peak_in_use_, slots_.size() - free_.size());
    }
    *writable = &slot->value;
    return Ref(slot);
  }

  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return slots_.size();
  }

  // Frees the free objects beyond the most that were in use at once since
  // the last trim (or now, if more) plus `spare`, at most once per `period`
  // (one thread, the owner, calls it often, e.g. once per loop). Objects in steady use are
  // never freed, so a steady state allocates nothing; a burst's objects go
  // one to two periods after it ends, even if nothing is acquired meanwhile.
  // Returns how many were freed.
  std::size_t Trim(std::size_t spare, std::chrono::steady_clock::duration period) {
    const auto now = std::chrono::steady_clock::now();
    if (now < next_trim_) return 0;
    next_trim_ = now + period;
    return TrimNow(spare);
  }

  // Trim without waiting for the period.
  std::size_t TrimNow(std::size_t spare) {
    std::vector<std::unique_ptr<typename Ref::Slot>> doomed;
    {
      std::lock_guard lock(mutex_);
      const std::size_t in_use = slots_.size() - free_.size();
      const std::size_t keep = std::max(peak_in_use_, in_use) + spare;
      peak_in_use_ = in_use;
      if (slots_.size() <= keep || free_.empty()) return 0;
      std::size_t excess = std::min(slots_.size() - keep, free_.size());
      doomed.reserve(excess);
      // The least recently returned go first (free_ is used from its back).
      const auto first_kept = free_.begin() + static_cast<std::ptrdiff_t>(excess);
      for (auto it = free_.begin(); it != first_kept; ++it) {
        const auto owner = std::find_if(slots_.begin(), slots_.end(), [&](const auto& p) { return p.get() == *it; });
        doomed.push_back(std::move(*owner));
        *owner = std::move(slots_.back());
        slots_.pop_back();
      }
      free_.erase(free_.begin(), first_kept);
    }
    const std::size_t freed = doomed.size();
    doomed.clear();  // outside the lock: large objects take a while to free
#if defined(__GLIBC__)
    // glibc keeps freed heap pages of its arenas mapped; hand them back.
    malloc_trim(0);
#endif
    return freed;
  }

 private:
  friend class PoolRef<T>;
  typename Ref::Slot* MakeSlot() {
    slots_.push_back(std::make_unique<typename Ref::Slot>());
    slots_.back()->pool = this;
    return slots_.back().get();
  }
  void Return(typename Ref::Slot* slot) {
    std::lock_guard lock(mutex_);
    free_.push_back(slot);
  }

  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<typename Ref::Slot>> slots_;
  std::vector<typename Ref::Slot*> free_;
  std::size_t peak_in_use_ = 0;  // most in use at once since the last trim
  std::chrono::steady_clock::time_point next_trim_{};
};

}  // namespace sim4cv::session
