#pragma once
// A lock-free ring of preallocated slots between exactly one producer thread and one
// consumer thread (the recorder's reading thread and its writer thread).
//
// Every slot is built once, in the constructor, as a copy of a prototype (so a slot may
// own buffers, e.g. a vector sized for one block of scans); afterwards nothing allocates.
// The producer fills a slot in place and publishes it; the consumer reads it in place
// and releases it. Neither side ever waits: a full ring gives the producer no slot (the
// caller decides what an overflow means), an empty ring gives the consumer none.
//
// Memory order: publish() stores the write counter with release after the slot is
// filled; the consumer loads it with acquire before reading the slot (and the other way
// round for release()), so a slot's contents are visible to the side that gets it.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>
#include <stdexcept>
#include <vector>

namespace doorbench {

template <typename Slot>
class SpscRing {
 public:
  // `capacity` slots (>= 1), each a copy of `prototype`.
  SpscRing(std::size_t capacity, const Slot& prototype) : slots_(check(capacity), prototype) {}
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const { return slots_.size(); }

  // Producer: the next free slot, or nullptr when the ring is full. The same slot is
  // returned until publish().
  Slot* producer_slot() {
    const std::uint64_t write = write_.load(std::memory_order_relaxed);
    if (write - read_.load(std::memory_order_acquire) >= slots_.size()) return nullptr;
    return &slots_[write % slots_.size()];
  }
  // Producer: hands the slot from producer_slot() (which must not have been nullptr) to
  // the consumer.
  void publish() {
    write_.store(write_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // Consumer: the oldest published slot, or nullptr when the ring is empty.
  const Slot* consumer_slot() const {
    const std::uint64_t read = read_.load(std::memory_order_relaxed);
    if (read == write_.load(std::memory_order_acquire)) return nullptr;
    return &slots_[read % slots_.size()];
  }
  // Consumer: gives the slot from consumer_slot() back to the producer.
  void release() {
    read_.store(read_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // Slots published and not yet released (exact only when both sides are idle).
  std::size_t size() const {
    return static_cast<std::size_t>(write_.load(std::memory_order_acquire) -
                                    read_.load(std::memory_order_acquire));
  }

 private:
  static std::size_t check(std::size_t capacity) {
    if (capacity == 0) throw std::invalid_argument("ring buffer capacity must be >= 1");
    return capacity;
  }

  std::vector<Slot> slots_;
  // 64-bit counters never wrap in practice (2^64 slots); apart on their own cache lines
  // so that the two threads do not invalidate each other's counter on every access.
  alignas(64) std::atomic<std::uint64_t> write_{0};
  alignas(64) std::atomic<std::uint64_t> read_{0};
};

}  // namespace doorbench
