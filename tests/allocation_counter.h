#pragma once
// test_allocation.cpp replaces the global operator new for the whole test binary and
// counts every call; any test can read the count to prove a path allocates nothing.
namespace doorbench::testing {
long long allocations();
}  // namespace doorbench::testing
