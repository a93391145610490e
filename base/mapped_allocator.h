// An allocator for arrays that grow, empty and are freed many times over (the replay's ray
// queues and worklists): blocks of kMappedBytes and more are mapped straight from the kernel
// and unmapped when freed, smaller ones come from operator new. Left to malloc, such blocks of
// every size end as holes in the heap that the next frame's arrays do not fill: resident,
// unused (docs/design.md §2 "What a replay holds"; b4096 `celltree-adaptive`, 8 processors:
// 47 MB of the peak).
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <new>

namespace raycell {

inline constexpr std::size_t kMappedBytes = std::size_t{128} << 10;

template <typename T>
struct MappedAllocator {
  using value_type = T;
  MappedAllocator() = default;
  template <typename U>
  MappedAllocator(const MappedAllocator<U>&) {}
  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kMappedBytes) return static_cast<T*>(::operator new(bytes));
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kMappedBytes) {
      ::operator delete(p);
    } else {
      munmap(p, bytes);
    }
  }
  friend bool operator==(const MappedAllocator&, const MappedAllocator&) { return true; }
  friend bool operator!=(const MappedAllocator&, const MappedAllocator&) { return false; }
};

}  // namespace raycell
