// The pending-event set of a model whose components each have at most one pending event
// (docs/design.md §2 "Events"): one slot per component, and a winner tree over the slots that
// names the earliest in the engine's order (engine/event.h EventBefore: time, then insertion
// order; every event here has priority 0). The replay's batch core runs on it
// (replay/replayer.cpp: a block processor's call for a cell, the end of its fetch or of its
// unit); a model whose components may have several pending events, or priorities, uses the
// general EventQueue and Simulator (engine/simulator.h).
//
// Schedule numbers every event it is given, as the Simulator does, so the same events are
// handled in the same order on either (tests/engine/slot_queue_test.cpp; the replay checks it
// field by field against tests/replay/reference_replayer.cpp).
//
// Each tree node holds its winner's key and nothing else: (time, seq << shift | slot), 16
// bytes. Updating a slot walks from its leaf to the root comparing the changed key with one
// sibling node per level (one load, no indirection through the slots) and picks the earlier
// without a branch (with several components the winner is unpredictable). seq is unique per
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
    nodes_.assign(2 * leaves_, Node{});
    for (std::uint32_t i = 0; i < leaves_; ++i) nodes_[leaves_ + i] = NodeOf(i);
    for (std::uint32_t k = leaves_ - 1; k >= 1; --k) {
      nodes_[k] = Earlier(nodes_[2 * k], nodes_[2 * k + 1]);
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
  std::uint32_t top() const { return std::uint32_t(nodes_[1].seq_index & (leaves_ - 1)); }

  // Brings the tree up to date with slot i; returns top() afterwards.
  std::uint32_t Update(std::uint32_t i) {
    Node cur = NodeOf(i);
    std::uint32_t k = leaves_ + i;
    nodes_[k] = cur;
    for (; k > 1; k /= 2) {
      cur = Earlier(cur, nodes_[k ^ 1]);
      nodes_[k / 2] = cur;
    }
    return std::uint32_t(cur.seq_index & (leaves_ - 1));
  }

  // Events scheduled so far.
  std::uint64_t scheduled() const { return next_seq_; }
  // The most events a queue of this many slots can number (the rest of the key's bits name
  // the slot): about 2^64 / slots.
  std::uint64_t max_events() const { return max_seq_ + 1; }

 private:
  struct Node {
    std::uint64_t time = UINT64_MAX, seq_index = UINT64_MAX;
  };
  // The earlier of two nodes (keys are distinct), selected without a branch.
  static Node Earlier(const Node& a, const Node& b) {
    using Key = unsigned __int128;
    const Key ka = Key{a.time} << 64 | a.seq_index, kb = Key{b.time} << 64 | b.seq_index;
    const std::uint64_t m = 0 - std::uint64_t{kb < ka};  // all ones: b
    return {a.time ^ ((a.time ^ b.time) & m), a.seq_index ^ ((a.seq_index ^ b.seq_index) & m)};
  }
  Node NodeOf(std::uint32_t i) const {
    return {slots_[i].time.picoseconds(), slots_[i].seq << shift_ | i};
  }

  std::uint32_t leaves_ = 1, shift_ = 0;
  std::uint64_t max_seq_ = 0, next_seq_ = 0;
  std::vector<Slot> slots_;
  std::vector<Node> nodes_;  // nodes_[1] the root; slot i's leaf at leaves_ + i
};

}  // namespace raycell
