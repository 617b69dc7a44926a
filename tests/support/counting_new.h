// Counts the global operator new calls of a test binary, for tests that prove a path allocates
// nothing. It replaces the global allocation functions: include it in exactly one source file of
// a binary, and give that test its own binary so other tests are not affected.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace whiskeye::test {
inline std::atomic<long> g_allocations{0};
// Allocations so far; compare two readings around the code under test.
inline long allocations() { return g_allocations.load(); }
}  // namespace whiskeye::test

// None of the three is inlined: with one side inlined (new as malloc, or delete as free), GCC 12
// pairs a malloc with an operator delete or an operator new with a free and raises
// -Wmismatched-new-delete (-O2 or -Os), which -Werror turns into a failed build.
[[gnu::noinline]] void* operator new(std::size_t n) {
  ++whiskeye::test::g_allocations;
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
