#pragma once
// allocation_counter.cpp replaces the global operator new for the whole test executable
// that calls allocations() and counts every call; any test can read the count to prove a
// path allocates nothing. Thread safety: the count is atomic.
namespace doorbench::testing {
long long allocations();
}  // namespace doorbench::testing
