#include "traces/columns.h"

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

void ColumnBuilder::Fill(schema::Column::Builder column) const {
  auto narrow = column.initNarrow(static_cast<unsigned>(narrow_.size()));
  for (unsigned i = 0; i < narrow_.size(); ++i) narrow.set(i, narrow_[i]);
  auto wide = column.initWide(static_cast<unsigned>(wide_.size()));
  for (unsigned i = 0; i < wide_.size(); ++i) wide.set(i, wide_[i]);
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
