// The single-producer single-consumer ring (acquisition/record/ring_buffer.h): order, full and
// empty, wrap-around, and two real threads passing a million numbered slots.
#include <array>
#include <catch2/catch.hpp>
#include <cstdint>
#include <thread>

#include "acquisition/record/ring_buffer.h"
#include "tests/support/allocation_counter.h"

using doorbench::SpscRing;

TEST_CASE("SpscRing: FIFO order, full and empty, wrap-around", "[ring]") {
  SpscRing<int> ring(3, -1);
  CHECK(ring.capacity() == 3);
  CHECK(ring.consumer_slot() == nullptr);
  int next_in = 0, next_out = 0;
  for (int round = 0; round < 50; ++round) {
    // Fill to the brim: the fourth slot is refused.
    for (int i = 0; i < 3; ++i) {
      int* slot = ring.producer_slot();
      REQUIRE(slot != nullptr);
      *slot = next_in++;
      ring.publish();
    }
    CHECK(ring.producer_slot() == nullptr);
    CHECK(ring.size() == 3);
    // Take two, put one, take the rest.
    for (int i = 0; i < 2; ++i) {
      const int* slot = ring.consumer_slot();
      REQUIRE(slot != nullptr);
      CHECK(*slot == next_out++);
      ring.release();
    }
    *ring.producer_slot() = next_in++;
    ring.publish();
    while (const int* slot = ring.consumer_slot()) {
      CHECK(*slot == next_out++);
      ring.release();
    }
    CHECK(ring.size() == 0);
  }
  CHECK(next_out == next_in);
}

TEST_CASE("SpscRing: capacity 0 is refused", "[ring]") {
  CHECK_THROWS_WITH((SpscRing<int>(0, 0)), "ring buffer capacity must be >= 1");
}

TEST_CASE("SpscRing: slots are built once, and using the ring allocates nothing", "[ring]") {
  struct Slot {
    std::vector<double> data;
  };
  SpscRing<Slot> ring(8, Slot{std::vector<double>(100)});
  const long long before = doorbench::testing::allocations();
  for (int i = 0; i < 1000; ++i) {
    Slot* slot = ring.producer_slot();
    REQUIRE(slot != nullptr);
    slot->data[static_cast<std::size_t>(i % 100)] = i;
    ring.publish();
    REQUIRE(ring.consumer_slot() != nullptr);
    ring.release();
  }
  CHECK(doorbench::testing::allocations() == before);
}

TEST_CASE("SpscRing: two threads pass a million numbered slots, none lost or reordered", "[ring]") {
  struct Slot {
    std::uint64_t number = 0;
    std::array<std::uint64_t, 7> copies{};  // the whole slot must arrive, not just a word
  };
  SpscRing<Slot> ring(64, Slot{});
  constexpr std::uint64_t kCount = 1'000'000;
  std::thread producer([&] {
    for (std::uint64_t n = 0; n < kCount;) {
      Slot* slot = ring.producer_slot();
      if (slot == nullptr) {
        std::this_thread::yield();
        continue;
      }
      slot->number = n;
      slot->copies.fill(n * 3 + 1);
      ring.publish();
      ++n;
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t bad = 0;
  while (expected < kCount) {
    const Slot* slot = ring.consumer_slot();
    if (slot == nullptr) {
      std::this_thread::yield();
      continue;
    }
    if (slot->number != expected) ++bad;
    for (const std::uint64_t copy : slot->copies) {
      if (copy != expected * 3 + 1) ++bad;
    }
    ring.release();
    ++expected;
  }
  producer.join();
  CHECK(bad == 0);
  CHECK(ring.consumer_slot() == nullptr);
}
