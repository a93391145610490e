// Text formatting shared by every printer: JSON string literals, CSV fields and numbers.
// Deterministic: the same value gives the same text on every machine.
#pragma once

#include <cstdint>
#include <string>

namespace raycell {

// JSON string literal with quotes: a"b -> "a\"b"; control characters as \uXXXX, UTF-8
// bytes passed through.
std::string JsonQuote(const std::string& s);
// A CSV field: quoted when it holds a comma, quote, CR or LF, with quotes doubled (RFC 4180).
std::string CsvField(const std::string& s);
// The shortest decimal that reads back to the same double ("0.1", "1e+300"); "nan", "inf",
// "-inf" for non-finite values.
std::string FormatReal(double v);
// A double as Python's repr() and str() write it (and so its csv module): the shortest digits
// that read back to it, in fixed notation with at least one decimal ("1.0", "0.25",
// "123456.5") when 1e-4 <= |v| < 1e16, else with an exponent of at least two digits
// ("1e-05", "1.5e-05", "1e+16"); "nan", "inf", "-inf" for non-finite values.
std::string FormatPythonFloat(double v);
// Fixed-point with `digits` decimals, as printf("%.*f"): FormatFixed(2.5, 2) == "2.50".
std::string FormatFixed(double v, int digits);
// 16 lowercase hexadecimal digits, no prefix: FormatHex64(255) == "00000000000000ff".
std::string FormatHex64(std::uint64_t v);

}  // namespace raycell
