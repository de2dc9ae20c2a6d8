// Reading and writing a decimal number as text; see decimal.hpp (docs/architecture.md "Where
// each concept lives").
#include "rendulic/core/decimal.hpp"

#include <locale.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include "rendulic/core/errors.hpp"

namespace rendulic {
namespace {

// The C locale's number conventions, for strtod_l: the decimal point is '.' whatever
// setlocale the process (or the Python session hosting it) called.
locale_t c_numeric() {
  static const locale_t c = newlocale(LC_NUMERIC_MASK, "C", static_cast<locale_t>(nullptr));
  return c;
}

}  // namespace

std::optional<double> decimal_number(const std::string& text) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return std::nullopt;
  if (text.find_first_of("xXpP") != std::string::npos) return std::nullopt;
  char* end = nullptr;
  // errno is not consulted: strtod sets ERANGE for a subnormal result too, which is a
  // number; an overflow shows as HUGE_VAL, which the finiteness check refuses.
  const locale_t c = c_numeric();
  const double v = c ? strtod_l(text.c_str(), &end, c) : std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string decimal_g(double v, int digits) {
  // std::to_chars with a precision is specified as printf in the C locale.
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, digits);
  return std::string(buf, r.ptr);
}

std::string decimal_fixed(double v, int decimals) {
  // %f of 1e308 has 309 digits before the point.
  char buf[400];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  return r.ec == std::errc{} ? std::string(buf, r.ptr) : decimal_g(v);
}

std::string decimal_text(double v) {
  if (!std::isfinite(v)) return decimal_g(v);
  for (int digits = 6; digits < 17; ++digits) {
    std::string s = decimal_g(v, digits);
    if (decimal_number(s) == v) return s;
  }
  return decimal_g(v, 17);
}

std::string not_a_decimal_number(const std::string& text) {
  // Appended, not "'" + ...: GCC 12 warns (-Wrestrict) on that form, falsely.
  std::string out = "'";
  out += printable(text);
  out += "' is not a finite decimal number";
  return out;
}

}  // namespace rendulic
