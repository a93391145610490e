// Allocators for large arrays, each a BlockAllocator: blocks from `Blocks::kFrom` bytes on come
// from Blocks (Allocate, Free), smaller ones from operator new.
//  - MappedAllocator: for arrays that grow, empty and are freed many times over (the replay's
//    ray queues and worklists), blocks of 128 KiB and more mapped straight from the kernel and
//    unmapped when freed. Left to malloc, such blocks of every size end as holes in the heap
//    that the next frame's arrays do not fill: resident, unused (docs/design.md §2 "What a
//    replay holds"; b4096 `celltree-adaptive`, 8 processors: 47 MB of the peak).
//  - HugePageAllocator: for records read at random (the replay's packed units), blocks of 2 MiB
//    and more 2 MiB aligned, whole 2 MiB pages, marked for transparent huge pages with madvise
//    (which this kernel setting needs): on 4 KiB pages nearly every such read also misses the
//    TLB.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <new>

namespace raycell {

template <typename T, typename Blocks>
struct BlockAllocator {
  using value_type = T;
  BlockAllocator() = default;
  template <typename U>
  BlockAllocator(const BlockAllocator<U, Blocks>&) {}
  template <typename U>
  struct rebind {
    using other = BlockAllocator<U, Blocks>;
  };
  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < Blocks::kFrom) return static_cast<T*>(::operator new(bytes));
    return static_cast<T*>(Blocks::Allocate(bytes));
  }
  void deallocate(T* p, std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < Blocks::kFrom) {
      ::operator delete(p);
    } else {
      Blocks::Free(p, bytes);
    }
  }
  friend bool operator==(const BlockAllocator&, const BlockAllocator&) { return true; }
  friend bool operator!=(const BlockAllocator&, const BlockAllocator&) { return false; }
};

struct MappedBlocks {
  static constexpr std::size_t kFrom = std::size_t{128} << 10;
  static void* Allocate(std::size_t bytes) {
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    return p;
  }
  static void Free(void* p, std::size_t bytes) { munmap(p, bytes); }
};

inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

struct HugePageBlocks {
  static constexpr std::size_t kFrom = kHugePageBytes;
  static void* Allocate(std::size_t bytes) {
    const std::size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
    void* p = std::aligned_alloc(kHugePageBytes, rounded);
    if (p == nullptr) throw std::bad_alloc();
    madvise(p, rounded, MADV_HUGEPAGE);  // a hint: without huge pages, 4 KiB pages as before
    return p;
  }
  static void Free(void* p, std::size_t) { std::free(p); }
};

template <typename T>
using MappedAllocator = BlockAllocator<T, MappedBlocks>;
template <typename T>
using HugePageAllocator = BlockAllocator<T, HugePageBlocks>;

}  // namespace raycell
