// A growable array of trivially copyable items for lists that grow, empty and are freed many
// times over (the replay's ray queues and worklists): the subset of std::vector they use, whose
// large blocks (from MappedBlocks::kFrom bytes) are mapped from the kernel as MappedAllocator's
// are, but grow in place with mremap: the kernel moves the pages already written instead of
// copying them into a fresh mapping, so a growing queue neither copies its items nor holds its
// old and new arrays at once, and its written pages are not faulted in and zeroed again
// (std::vector's copies into fresh mappings were 2-3% of a watching replay's CPU at 1920x1080
// and 4096 cells, BENCHMARKS.md "The cost of deciding"), and shrink in place too (a Cell
// Tree's arrays, reserved for its frame's visits and fitted to its nodes once built). Smaller
// blocks come from malloc. Growth doubles the room, as std::vector's does.
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>
#include <utility>

#include "base/kept_room.h"
#include "base/mapped_allocator.h"

namespace raycell {

template <typename T>
class MappedArray {
  static_assert(std::is_trivially_copyable_v<T>, "items are moved as bytes");

 public:
  using value_type = T;
  using iterator = T*;
  using const_iterator = const T*;

  MappedArray() = default;
  MappedArray(MappedArray&& o) noexcept
      : data_(std::exchange(o.data_, nullptr)),
        size_(std::exchange(o.size_, 0)),
        capacity_(std::exchange(o.capacity_, 0)),
        bytes_(std::exchange(o.bytes_, 0)) {}
  MappedArray& operator=(MappedArray&& o) noexcept {
    if (this != &o) {
      Release();
      data_ = std::exchange(o.data_, nullptr);
      size_ = std::exchange(o.size_, 0);
      capacity_ = std::exchange(o.capacity_, 0);
      bytes_ = std::exchange(o.bytes_, 0);
    }
    return *this;
  }
  // A copy holds the items alone (its room is their size).
  MappedArray(const MappedArray& o) { append(o.begin(), o.end()); }
  MappedArray& operator=(const MappedArray& o) {
    if (this != &o) {
      clear();
      append(o.begin(), o.end());
    }
    return *this;
  }
  ~MappedArray() { Release(); }

  std::size_t size() const { return size_; }
  std::size_t capacity() const { return capacity_; }
  bool empty() const { return size_ == 0; }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

  void push_back(const T& item) {
    if (size_ == capacity_) Grow(size_ + 1);
    data_[size_++] = item;
  }
  // Appends [first, last), which must not lie in this array.
  void append(const T* first, const T* last) {
    const std::size_t n = std::size_t(last - first);
    if (n == 0) return;
    if (size_ + n > capacity_) Grow(size_ + n);
    std::memcpy(static_cast<void*>(data_ + size_), first, n * sizeof(T));
    size_ += n;
  }
  // n copies of `value` (the room is kept, and grows if n needs more).
  void assign(std::size_t n, const T& value) {
    size_ = 0;
    resize(n, value);
  }
  // Room for at least n items (never less than the room it has).
  void reserve(std::size_t n) {
    if (n > capacity_) Grow(n);
  }
  // n items: the first min(n, size()) kept, the others value-initialised.
  void resize(std::size_t n) { resize(n, T{}); }
  // n items: the first min(n, size()) kept, the others copies of `value`.
  void resize(std::size_t n, const T& value) {
    if (n > capacity_) Grow(n);
    for (std::size_t i = size_; i < n; ++i) data_[i] = value;
    size_ = n;
  }
  // Drops the first n items, keeping the others in order.
  void erase_front(std::size_t n) {
    n = std::min(n, size_);
    if (n == 0) return;
    std::memmove(static_cast<void*>(data_), data_ + n, (size_ - n) * sizeof(T));
    size_ -= n;
  }
  // Shrinks to n items (n <= size()); the room is kept.
  void truncate(std::size_t n) { size_ = std::min(n, size_); }
  void clear() { size_ = 0; }
  void swap(MappedArray& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    std::swap(capacity_, o.capacity_);
    std::swap(bytes_, o.bytes_);
  }
  // Room for its items alone: a mapped block shrinks in place (its pages past the items go back
  // to the kernel; nothing is copied), a smaller one by realloc.
  void shrink_to_fit() {
    if (size_ == capacity_ || data_ == nullptr) return;
    if (size_ == 0) {
      free_room();
      return;
    }
    const std::size_t need = size_ * sizeof(T);
    if (Mapped(bytes_)) {
      const std::size_t page = PageBytes();
      const std::size_t bytes = std::max((need + page - 1) / page * page, MappedBlocks::kFrom);
      if (bytes >= bytes_) return;
      if (mremap(data_, bytes_, bytes, 0) == MAP_FAILED) return;  // kept as it was
      bytes_ = bytes;
    } else {
      void* p = std::realloc(data_, need);
      if (p == nullptr) return;
      data_ = static_cast<T*>(p);
      bytes_ = need;
    }
    capacity_ = bytes_ / sizeof(T);
  }
  // Empties the array and frees its room.
  void free_room() {
    Release();
    data_ = nullptr;
    size_ = capacity_ = bytes_ = 0;
  }

 private:
  static std::size_t PageBytes() {
    static const std::size_t page = std::size_t(sysconf(_SC_PAGESIZE));
    return page;
  }
  static bool Mapped(std::size_t bytes) { return bytes >= MappedBlocks::kFrom; }

  // Room for at least `need` items: twice the room, or `need` if more.
  void Grow(std::size_t need) {
    std::size_t items = std::max<std::size_t>({need, 2 * capacity_, 4});
    if (items > (std::size_t(-1) / 2) / sizeof(T)) throw std::bad_alloc();
    std::size_t bytes = items * sizeof(T);
    const std::size_t old_bytes = bytes_;
    void* p = nullptr;
    if (Mapped(bytes)) {
      const std::size_t page = PageBytes();
      bytes = (bytes + page - 1) / page * page;
      if (data_ != nullptr && Mapped(old_bytes)) {
        p = mremap(data_, old_bytes, bytes, MREMAP_MAYMOVE);
        if (p == MAP_FAILED) throw std::bad_alloc();
      } else {
        p = MappedBlocks::Allocate(bytes);
        if (size_ != 0) std::memcpy(p, static_cast<const void*>(data_), size_ * sizeof(T));
        std::free(data_);
      }
    } else {
      p = std::realloc(data_, bytes);
      if (p == nullptr) throw std::bad_alloc();
    }
    data_ = static_cast<T*>(p);
    bytes_ = bytes;
    capacity_ = bytes / sizeof(T);
  }

  void Release() {
    if (data_ == nullptr) return;
    if (Mapped(bytes_)) {
      MappedBlocks::Free(data_, bytes_);
    } else {
      std::free(data_);
    }
  }

  T* data_ = nullptr;
  std::size_t size_ = 0, capacity_ = 0;
  std::size_t bytes_ = 0;  // the block's bytes: mapped (whole pages) from MappedBlocks::kFrom on
};

// Empties `v` and frees its room (kept_room.h's FreeRoom for std::vector; its
// ReleaseRoomAbove calls either).
template <typename T>
void FreeRoom(MappedArray<T>& v) {
  v.free_room();
}

}  // namespace raycell
