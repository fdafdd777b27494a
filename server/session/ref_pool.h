// A fixed set of reusable objects handed out with an intrusive reference
// count, so the hot path publishes a frame to many readers without a heap
// allocation: the sim thread fills a pooled object, readers share it
// read-only, and the last release returns it to the pool.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

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
    }
    *writable = &slot->value;
    return Ref(slot);
  }

  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return slots_.size();
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
};

}  // namespace sim4cv::session
