// Reading a decimal number from text; see decimal.hpp (docs/architecture.md "Where each concept
// lives").
#include "rendulic/core/decimal.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>

namespace rendulic {

std::optional<double> decimal_number(const std::string& text) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return std::nullopt;
  if (text.find_first_of("xXpP") != std::string::npos) return std::nullopt;
  char* end = nullptr;
  // errno is not consulted: strtod sets ERANGE for a subnormal result too, which is a
  // number; an overflow shows as HUGE_VAL, which the finiteness check refuses.
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace rendulic
