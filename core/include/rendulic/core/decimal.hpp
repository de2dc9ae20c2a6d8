// The one reading of a number written as text (a CSV field, a packing file's token, a
// --value): decimal, finite, the whole text (docs/architecture.md "Where each concept lives").
#pragma once

#include <optional>
#include <string>

namespace rendulic {

// The value of `text` when all of it is one finite decimal number ("1.5", "-2e-3", "+4");
// nullopt for anything else: empty, leading blanks, trailing characters, hexadecimal (strtod
// reads "0x10" as sixteen), nan, inf, or a magnitude beyond the largest double. A magnitude
// below the smallest normal double is read as the nearest subnormal or zero, as every other
// reader of such a file does: an underflow is not an error of the data.
std::optional<double> decimal_number(const std::string& text);

}  // namespace rendulic
