// The integer columns of trace batches, written and read (see "Column encoding" and
// "Samples" in traces/trace.capnp): a Column holds one byte per value, 255 escaping the value
// into a list of 64-bit words; a zero-run coded Column also folds runs of zeros into the
// digits of their length. Zigzag codes carry signed deltas.
//
// Writer and reader share this code; the reader checks everything it reads and throws
// BadTraceData (which it turns into an InputError naming the file and frame).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "traces/trace.capnp.h"

namespace raycell {

// Bad bytes found while decoding a trace; the reader adds the file and the part of it.
class BadTraceData : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// zigzag(d) = (d << 1) ^ (d >> 63): 0, -1, 1, -2, 2 -> 0, 1, 2, 3, 4.
inline std::uint64_t ZigZag(std::int64_t v) {
  return (static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63);
}
inline std::int64_t UnZigZag(std::uint64_t code) {
  return static_cast<std::int64_t>(code >> 1) ^ -static_cast<std::int64_t>(code & 1);
}
// value - previous as a signed delta (two's complement wrap-around).
inline std::int64_t Delta(std::uint64_t value, std::uint64_t previous) {
  return static_cast<std::int64_t>(value - previous);
}
// previous + unzigzag(code), which must fit a uint32; BadTraceData "bad WHAT delta" if not.
std::uint32_t ApplyDelta(std::uint64_t previous, std::uint64_t code, const char* what);

// ---- Cell steps (format version 5; see "Paths" in trace.capnp) --------------------------

// A step code: 0..124 is (dx + 2) + 5 * (dy + 2) + 25 * (dz + 2) for a step of at most 2
// cells along every axis; kStepEscape is followed by zigzag(dx), zigzag(dy), zigzag(dz).
inline constexpr std::uint64_t kStepEscape = 125;
// The cell grid nx x ny x nz that cell ids number (cell = x + nx * (y + ny * z)).
using CellGrid = std::array<std::uint32_t, 3>;

// ---- Writing -----------------------------------------------------------------------------

// A Column being built: narrow bytes with 255 escaping into `wide`.
class ColumnBuilder {
 public:
  void Add(std::uint64_t v) {
    if (v < 255) {
      narrow_.push_back(static_cast<std::uint8_t>(v));
    } else {
      narrow_.push_back(255);
      wide_.push_back(v);
    }
  }
  void Fill(schema::Column::Builder column) const;
  // Bytes of the column's lists (without Cap'n Proto's framing).
  std::size_t bytes() const { return narrow_.size() + 8 * wide_.size(); }
  // Appends those bytes to `out` (the narrow bytes, then each wide value's 8, little-endian).
  void AppendTo(std::string& out) const;
  // The order-0 entropy of the narrow bytes plus 64 bits per wide value: an estimate of
  // what zstd makes of the column.
  double EntropyBits() const;

 private:
  std::vector<std::uint8_t> narrow_;
  std::vector<std::uint64_t> wide_;
};

// A zero-run coded Column (see "Samples" in trace.capnp): a run of n zeros is written as
// the digits of n in bijective base 2 (digit 1 -> 0, digit 2 -> 1, least significant
// first), any other value v as v + 1. Values are at most kMaxValue.
class ZeroRunColumnBuilder {
 public:
  static constexpr std::uint64_t kMaxValue = ~std::uint64_t{0} - 1;
  void Add(std::uint64_t v);
  // Ends the column; call once, before Fill().
  void Finish() { FlushZeros(); }
  void Fill(schema::Column::Builder column) const { column_.Fill(column); }
  std::size_t bytes() const { return column_.bytes(); }
  double EntropyBits() const { return column_.EntropyBits(); }

 private:
  void FlushZeros();

  ColumnBuilder column_;
  std::uint64_t zeros_ = 0;
};

// Adds the step from cell `from` to cell `to` of `grid` to `column` (one value, or four with
// the escape).
void AddStep(ColumnBuilder& column, std::uint32_t from, std::uint32_t to, const CellGrid& grid);
// The code of the step from cell `from` to cell `to` of `grid` (AddStep's first value) and,
// for kStepEscape, the zigzag of each axis's difference in `escape`.
unsigned StepCode(std::uint32_t from, std::uint32_t to, const CellGrid& grid,
                  std::uint64_t escape[3]);

// The order-0 entropy of `bytes`, in bits.
double EntropyBits(const std::vector<std::uint8_t>& bytes);

// ---- Reading -----------------------------------------------------------------------------

// Reads a Column value by value, checking its escapes and that it has as many values as
// the decoding asks for. `name` (a string literal) names the column in messages.
class ColumnReader {
 public:
  ColumnReader(schema::Column::Reader c, const char* name)
      : narrow_(c.getNarrow()), wide_(c.getWide()), name_(name) {}
  // Also checks that the column has exactly `expected` values.
  ColumnReader(schema::Column::Reader c, std::size_t expected, const char* name);
  bool AtEnd() const { return next_ == narrow_.size(); }
  std::uint64_t Next() {
    const std::uint64_t v = Peek();
    wide_next_ += narrow_[next_] == 255;
    ++next_;
    return v;
  }
  // The next value, left unread.
  std::uint64_t Peek() const {
    if (AtEnd()) Fail(": too few values");
    const std::uint8_t b = narrow_[next_];
    if (b < 255) return b;
    if (wide_next_ == wide_.size()) Fail(": bad escape");
    return wide_[wide_next_];
  }
  // Checks that every value (narrow and wide) was read.
  void Finish() const;
  const char* name() const { return name_; }
  // Throws BadTraceData "column NAME<what>".
  [[noreturn]] void Fail(const char* what) const;

 private:
  capnp::List<std::uint8_t>::Reader narrow_;
  capnp::List<std::uint64_t>::Reader wide_;
  const char* name_;
  unsigned next_ = 0, wide_next_ = 0;
};

// Reads a zero-run coded Column (see "Samples" in trace.capnp). A run has at most 40
// digits (fewer than 2^41 zeros).
class ZeroRunColumnReader {
 public:
  ZeroRunColumnReader(schema::Column::Reader c, const char* name) : column_(c, name) {}
  std::uint64_t Next() {
    if (zeros_ > 0) {
      --zeros_;
      return 0;
    }
    const std::uint64_t v = column_.Next();
    return v >= 2 ? v - 1 : StartRun(v);
  }
  void Finish() const;

 private:
  // Reads the rest of a run whose first digit code is `v`; returns its first zero.
  std::uint64_t StartRun(std::uint64_t v);

  ColumnReader column_;
  std::uint64_t zeros_ = 0;  // zeros of the current run not yet returned
};

// The cell a step read from `column` leads to from cell `from` of `grid` (whose cells number
// fewer than 2^32 - 1), or kBadStep when it leaves the grid or its code is not one.
inline constexpr std::uint32_t kBadStep = ~std::uint32_t{0};
std::uint32_t ReadStep(ColumnReader& column, std::uint32_t from, const CellGrid& grid);
// The cell the step of code `code` (0..kStepEscape; for kStepEscape, the zigzag of each axis's
// difference in `escape`) leads to from cell `from` of `grid`, or kBadStep. Inline: every
// reader of a path calls it once a visit.
inline std::uint32_t StepTo(std::uint32_t from, std::uint64_t code, const std::uint64_t escape[3],
                            const CellGrid& grid) {
  const std::int64_t nx = grid[0], nxy = std::int64_t{grid[0]} * grid[1];
  const std::int64_t a = from;
  std::int64_t d[3];
  if (code < kStepEscape) {
    d[0] = static_cast<std::int64_t>(code % 5) - 2;
    d[1] = static_cast<std::int64_t>(code / 5 % 5) - 2;
    d[2] = static_cast<std::int64_t>(code / 25) - 2;
  } else if (code == kStepEscape) {
    for (int axis = 0; axis < 3; ++axis) {
      const std::uint64_t z = escape[axis];
      d[axis] = z > (std::uint64_t{1} << 34) ? std::int64_t{1} << 34 : UnZigZag(z);
    }
  } else {
    return kBadStep;
  }
  const std::int64_t at[3] = {a % nx + d[0], a % nxy / nx + d[1], a / nxy + d[2]};
  for (int axis = 0; axis < 3; ++axis) {
    if (at[axis] < 0 || at[axis] >= std::int64_t{grid[axis]}) return kBadStep;
  }
  return static_cast<std::uint32_t>(at[0] + nx * at[1] + nxy * at[2]);
}

}  // namespace raycell
