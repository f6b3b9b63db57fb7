// counting_new.hpp — a counting operator new for the benchmark programs that report heap
// allocations per frame (load_curve, frame_cpu). It replaces the program's global operator
// new/delete, so include it in exactly one .cpp file of a program. g_news / g_bytes count
// every allocation (calls and bytes) since the start; read them before and after the code
// under test.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace findmug::bench {
inline std::atomic<std::uint64_t> g_news{0}, g_bytes{0};
}  // namespace findmug::bench

void* operator new(std::size_t size) {
  findmug::bench::g_news.fetch_add(1, std::memory_order_relaxed);
  findmug::bench::g_bytes.fetch_add(size, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
// The nothrow forms too (std::stable_partition's temporary buffer uses them): left to
// the library, their memory would come from another allocator than the free() above,
// which ASan reports as an alloc-dealloc mismatch.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  findmug::bench::g_news.fetch_add(1, std::memory_order_relaxed);
  findmug::bench::g_bytes.fetch_add(size, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
