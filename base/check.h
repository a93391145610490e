// Two error channels (CONTRIBUTING.md "Errors"):
//  - InputError: bad input (files, options, configs). The message names the file, record or
//    option and what was expected; tools print it and exit non-zero.
//  - RAYCELL_CHECK: a broken invariant, a bug. Prints the condition and values and aborts.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

namespace raycell {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
[[noreturn]] inline void CheckFailed(const char* cond, const char* file, int line,
                                     const std::string& values) {
  std::fprintf(stderr, "%s:%d: CHECK failed: %s %s\n", file, line, cond, values.c_str());
  std::abort();
}
template <typename A, typename B>
std::string Values(const A& a, const B& b) {
  std::ostringstream s;
  s << "(" << a << " vs " << b << ")";
  return s.str();
}
}  // namespace detail

}  // namespace raycell

#define RAYCELL_CHECK(cond)                                                     \
  do {                                                                          \
    if (!(cond)) ::raycell::detail::CheckFailed(#cond, __FILE__, __LINE__, ""); \
  } while (0)

#define RAYCELL_CHECK_OP(a, op, b)                                          \
  do {                                                                      \
    if (!((a)op(b)))                                                        \
      ::raycell::detail::CheckFailed(#a " " #op " " #b, __FILE__, __LINE__, \
                                     ::raycell::detail::Values((a), (b)));  \
  } while (0)

#define RAYCELL_CHECK_EQ(a, b) RAYCELL_CHECK_OP(a, ==, b)
#define RAYCELL_CHECK_LT(a, b) RAYCELL_CHECK_OP(a, <, b)
#define RAYCELL_CHECK_LE(a, b) RAYCELL_CHECK_OP(a, <=, b)
