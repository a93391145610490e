// The pending-event set of a model whose components each have at most one pending event
// (docs/design.md §2 "Events"): one slot per component, and a winner tree over the slots that
// names the earliest in the engine's order (engine/event.h EventBefore: time, then insertion
// order; every event here has priority 0). The replay's batch core runs on it
// (replay/replayer.cpp: a block processor's call for a cell, the end of its fetch or of its
// unit); a model whose components may have several pending events, or priorities, uses the
// general EventQueue and Simulator (tests/oracle/simulator.h).
//
// Schedule numbers every event it is given, as the Simulator does, so the same events are
// handled in the same order on either (tests/engine/slot_queue_test.cpp; the replay checks it
// field by field against tests/oracle/reference_replayer.cpp).
//
// Each tree node holds its winner's key and nothing else: (time, seq << shift | slot), in two
// arrays of 64-bit words (a node's index is a scaled address, no multiply). Updating a slot
// walks from its leaf to the root comparing the changed key with one sibling node per level
// (two loads, no indirection through the slots) and picks the earlier without a branch (with
// several components the winner is unpredictable): on x86-64 a 128-bit subtraction's borrow
// and two conditional moves, written as such since compilers make a branch of the selection
// or a longer mask sequence (14 instructions a level, 19 with masks). seq is unique per
// pending event, so the slot index below it changes no order; it only names the winner, and
// among empty slots (seq all ones) makes the left one win. The earliest slot is known in
// O(1), a changed slot costs O(log slots).
#pragma once

#include <cstdint>
#include <vector>

#include "base/check.h"
#include "engine/time.h"

namespace raycell {

// Kind: the model's event kinds, an enum whose value-initialised Kind{} means "nothing
// pending".
template <typename Kind>
class SlotQueue {
 public:
  struct Slot {
    SimTime time = SimTime::Max();
    std::uint64_t seq = UINT64_MAX;  // UINT64_MAX with time Max: nothing pending
    Kind kind{};
  };

  // `slots` components, none with an event pending.
  explicit SlotQueue(std::uint32_t slots) : slots_(slots) {
    while (leaves_ < slots) leaves_ *= 2, ++shift_;
    max_seq_ = (UINT64_MAX >> shift_) - 1;
    slots_.resize(leaves_);  // padding slots stay empty forever
    time_.assign(2 * leaves_, UINT64_MAX);
    key_.assign(2 * leaves_, UINT64_MAX);
    for (std::uint32_t i = 0; i < leaves_; ++i) {
      time_[leaves_ + i] = slots_[i].time.picoseconds();
      key_[leaves_ + i] = slots_[i].seq << shift_ | i;
    }
    for (std::size_t k = leaves_ - 1; k >= 1; --k) {
      std::uint64_t t = time_[2 * k], key = key_[2 * k];
      KeepEarlier(t, key, time_[2 * k + 1], key_[2 * k + 1]);
      time_[k] = t, key_[k] = key;
    }
  }

  // Slot i, to be read or written in place, field by field (copying a whole slot just written
  // would stall on store forwarding). After a change, Update(i) before top() is read.
  Slot& at(std::uint32_t i) { return slots_[i]; }
  const Slot& at(std::uint32_t i) const { return slots_[i]; }

  // Gives slot i, which has nothing pending, the event (when, kind) and the next insertion
  // number. The tree sees it at the next Update(i).
  void Schedule(std::uint32_t i, SimTime when, Kind kind) {
    Slot& s = slots_[i];
    RAYCELL_CHECK(s.kind == Kind{});
    RAYCELL_CHECK_LE(next_seq_, max_seq_);
    s.time = when;
    s.seq = next_seq_++;
    s.kind = kind;
  }

  // Empties slot i: its event is being handled (its handler may Schedule the next). The tree
  // sees it at the next Update(i).
  void Clear(std::uint32_t i) {
    Slot& s = slots_[i];
    s.time = SimTime::Max();
    s.seq = UINT64_MAX;
    s.kind = Kind{};
  }

  // The earliest slot's index, as of the last Updates; its kind is Kind{} when nothing is
  // pending.
  std::uint32_t top() const { return std::uint32_t(key_[1] & (leaves_ - 1)); }

  // Brings the tree up to date with slot i; returns top() afterwards.
  std::uint32_t Update(std::uint32_t i) {
    std::uint64_t t = slots_[i].time.picoseconds(), key = slots_[i].seq << shift_ | i;
    std::uint64_t* const time = time_.data();
    std::uint64_t* const keys = key_.data();
    std::size_t k = std::size_t{leaves_} + i;
    time[k] = t, keys[k] = key;
    for (; k > 1; k /= 2) {
      KeepEarlier(t, key, time[k ^ 1], keys[k ^ 1]);
      time[k / 2] = t, keys[k / 2] = key;
    }
    return std::uint32_t(key & (leaves_ - 1));
  }

  // Numbers n events that the model keeps outside the slots (the replay's woken processors,
  // replay/replayer.cpp), as n Schedules would: returns the first number, the others follow.
  std::uint64_t TakeSeqs(std::uint64_t n) {
    RAYCELL_CHECK_LE(n, max_seq_ + 1 - next_seq_);
    const std::uint64_t first = next_seq_;
    next_seq_ += n;
    return first;
  }

  // Events scheduled so far.
  std::uint64_t scheduled() const { return next_seq_; }
  // The most events a queue of this many slots can number (the rest of the key's bits name
  // the slot): about 2^64 / slots.
  std::uint64_t max_events() const { return max_seq_ + 1; }

  // (t, key) becomes the earlier of itself and (bt, bkey) (keys are distinct), without a
  // branch: with several components the winner is unpredictable. Public for its test, which
  // checks the x86-64 form against the portable one.
  static void KeepEarlier(std::uint64_t& t, std::uint64_t& key, std::uint64_t bt,
                          std::uint64_t bkey) {
#if defined(__x86_64__)
    // (bt, bkey) - (t, key) borrows iff b is earlier; then both move (compilers make a
    // branch of the portable form's selection, or a longer mask sequence).
    std::uint64_t scratch;
    asm("cmp %[key], %[bkey]\n\t"
        "mov %[bt], %[scratch]\n\t"
        "sbb %[t], %[scratch]\n\t"
        "cmovb %[bt], %[t]\n\t"
        "cmovb %[bkey], %[key]"
        : [t] "+&r"(t), [key] "+&r"(key), [scratch] "=&r"(scratch)
        : [bt] "r"(bt), [bkey] "r"(bkey)
        : "cc");
#else
    KeepEarlierPortable(t, key, bt, bkey);
#endif
  }
  // The same with masks, for any platform.
  static void KeepEarlierPortable(std::uint64_t& t, std::uint64_t& key, std::uint64_t bt,
                                  std::uint64_t bkey) {
    using Key = unsigned __int128;
    const std::uint64_t m = 0 - std::uint64_t{(Key{bt} << 64 | bkey) < (Key{t} << 64 | key)};
    t ^= (t ^ bt) & m;
    key ^= (key ^ bkey) & m;
  }

 private:
  std::uint32_t leaves_ = 1, shift_ = 0;
  std::uint64_t max_seq_ = 0, next_seq_ = 0;
  std::vector<Slot> slots_;
  // Node k's winner: time_[k], key_[k]; node 1 the root, slot i's leaf at leaves_ + i.
  std::vector<std::uint64_t> time_, key_;
};

}  // namespace raycell
