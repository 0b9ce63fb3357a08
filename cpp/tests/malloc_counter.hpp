// Counts heap allocations made through malloc, calloc, realloc and operator new (which goes
// through malloc in libstdc++) while a Count guard is alive. Include in exactly one source file
// of a test program: it replaces the C allocation functions of that program.
#pragma once

#include <malloc.h>

#include <atomic>
#include <cstddef>

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
}

namespace mindyn::test {
inline std::atomic<bool> counting{false};
inline std::atomic<long> allocations{0};

struct Count {
  Count() {
    allocations = 0;
    counting = true;
  }
  ~Count() { counting = false; }
  long value() const { return allocations.load(); }
};
}  // namespace mindyn::test

extern "C" void* malloc(size_t size) {
  if (mindyn::test::counting.load(std::memory_order_relaxed))
    mindyn::test::allocations.fetch_add(1);
  return __libc_malloc(size);
}
extern "C" void* calloc(size_t n, size_t size) {
  if (mindyn::test::counting.load(std::memory_order_relaxed))
    mindyn::test::allocations.fetch_add(1);
  return __libc_calloc(n, size);
}
extern "C" void* realloc(void* p, size_t size) {
  if (mindyn::test::counting.load(std::memory_order_relaxed))
    mindyn::test::allocations.fetch_add(1);
  return __libc_realloc(p, size);
}
