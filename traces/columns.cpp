#include "traces/columns.h"

#include <cmath>
#include <cstdlib>

#include "base/check.h"

namespace raycell {

std::uint32_t ApplyDelta(std::uint64_t previous, std::uint64_t code, const char* what) {
  if (code > (std::uint64_t{1} << 34)) throw BadTraceData(std::string("bad ") + what + " delta");
  const std::int64_t v = static_cast<std::int64_t>(previous) + UnZigZag(code);
  if (v < 0 || v > std::int64_t{0xFFFFFFFF}) {
    throw BadTraceData(std::string("bad ") + what + " delta");
  }
  return static_cast<std::uint32_t>(v);
}

double EntropyBits(const std::vector<std::uint8_t>& bytes) {
  std::size_t counts[256] = {};
  for (const std::uint8_t b : bytes) ++counts[b];
  const double n = static_cast<double>(bytes.size());
  double bits = 0;
  for (const std::size_t c : counts) {
    if (c > 0) bits += static_cast<double>(c) * std::log2(n / static_cast<double>(c));
  }
  return bits;
}

double ColumnBuilder::EntropyBits() const {
  return raycell::EntropyBits(narrow_) + 64.0 * static_cast<double>(wide_.size());
}

void ColumnBuilder::Fill(schema::Column::Builder column) const {
  auto narrow = column.initNarrow(static_cast<unsigned>(narrow_.size()));
  for (unsigned i = 0; i < narrow_.size(); ++i) narrow.set(i, narrow_[i]);
  auto wide = column.initWide(static_cast<unsigned>(wide_.size()));
  for (unsigned i = 0; i < wide_.size(); ++i) wide.set(i, wide_[i]);
}

void ColumnBuilder::AppendTo(std::string& out) const {
  out.append(reinterpret_cast<const char*>(narrow_.data()), narrow_.size());
  for (const std::uint64_t w : wide_) {
    for (int k = 0; k < 8; ++k) out.push_back(static_cast<char>(w >> (8 * k)));
  }
}

void AddStep(ColumnBuilder& column, std::uint32_t from, std::uint32_t to, const CellGrid& grid) {
  std::uint64_t escape[3];
  const unsigned code = StepCode(from, to, grid, escape);
  column.Add(code);
  if (code == kStepEscape) {
    for (const std::uint64_t z : escape) column.Add(z);
  }
}

unsigned StepCode(std::uint32_t from, std::uint32_t to, const CellGrid& grid,
                  std::uint64_t escape[3]) {
  const std::int64_t nx = grid[0], nxy = std::int64_t{grid[0]} * grid[1];
  const std::int64_t a = from, b = to;
  const std::int64_t dx = b % nx - a % nx, dy = b % nxy / nx - a % nxy / nx, dz = b / nxy - a / nxy;
  if (std::abs(dx) <= 2 && std::abs(dy) <= 2 && std::abs(dz) <= 2) {
    return static_cast<unsigned>((dx + 2) + 5 * (dy + 2) + 25 * (dz + 2));
  }
  escape[0] = ZigZag(dx), escape[1] = ZigZag(dy), escape[2] = ZigZag(dz);
  return kStepEscape;
}

void ZeroRunColumnBuilder::Add(std::uint64_t v) {
  if (v == 0) {
    ++zeros_;
    return;
  }
  RAYCELL_CHECK_LE(v, kMaxValue);
  FlushZeros();
  column_.Add(v + 1);
}

void ZeroRunColumnBuilder::FlushZeros() {
  // Odd n: digit 1, n -> (n - 1) / 2; even n: digit 2, n -> (n - 2) / 2 == (n - 1) / 2.
  for (std::uint64_t n = zeros_; n > 0; n = (n - 1) / 2) column_.Add((n & 1) ? 0 : 1);
  zeros_ = 0;
}

ColumnReader::ColumnReader(schema::Column::Reader c, std::size_t expected, const char* name)
    : ColumnReader(c, name) {
  if (narrow_.size() != expected) {
    throw BadTraceData(std::string("column ") + name + " has " + std::to_string(narrow_.size()) +
                       " values, expected " + std::to_string(expected));
  }
}

void ColumnReader::Finish() const {
  if (!AtEnd() || wide_next_ != wide_.size()) Fail(": extra values");
}

void ColumnReader::Fail(const char* what) const {
  throw BadTraceData(std::string("column ") + name_ + what);
}

std::uint32_t ReadStep(ColumnReader& column, std::uint32_t from, const CellGrid& grid) {
  const std::uint64_t code = column.Next();
  std::uint64_t escape[3] = {0, 0, 0};
  if (code == kStepEscape) {
    for (std::uint64_t& z : escape) z = column.Next();
  }
  return StepTo(from, code, escape, grid);
}

std::uint64_t ZeroRunColumnReader::StartRun(std::uint64_t v) {
  // Bijective base-2 digits, least significant first, up to a value >= 2 or the end.
  std::uint64_t run = 0;
  for (int digit = 0;; ++digit) {
    if (digit == 40) column_.Fail(": bad zero run");
    run += (v + 1) << digit;
    if (column_.AtEnd() || column_.Peek() >= 2) break;
    v = column_.Next();
  }
  zeros_ = run - 1;
  return 0;
}

void ZeroRunColumnReader::Finish() const {
  if (zeros_ > 0) column_.Fail(": extra values");
  column_.Finish();
}

}  // namespace raycell
