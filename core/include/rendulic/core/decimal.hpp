// The one reading and writing of a number as text (a CSV field, a packing file's token, a
// --value, a scenario value, a group's name): decimal, finite, the whole text, and the same
// whatever the process's C locale says (docs/architecture.md "Where each concept lives").
#pragma once

#include <optional>
#include <string>

namespace rendulic {

// The value of `text` when all of it is one finite decimal number ("1.5", "-2e-3", "+4");
// nullopt for anything else: empty, leading blanks, trailing characters, hexadecimal (strtod
// reads "0x10" as sixteen), nan, inf, or a magnitude beyond the largest double. A magnitude
// below the smallest normal double is read as the nearest subnormal or zero, as every other
// reader of such a file does: an underflow is not an error of the data. The decimal point is
// '.', also where a Python session set a locale with a decimal comma (locale.setlocale), under
// which strtod stops at the '.'.
std::optional<double> decimal_number(const std::string& text);

// v in `digits` significant digits as printf's %g writes it in the C locale ("0.66", "5e-05",
// "3000", "inf"): the text of a number in a group's name and in messages. printf itself follows
// the process's locale and wrote "0,66" in a session with a decimal comma.
std::string decimal_g(double v, int digits = 6);

// v with `decimals` digits after the point as printf's %.*f writes it in the C locale ("2.5",
// "47"): the text of a number in messages that give a fixed number of decimals.
std::string decimal_fixed(double v, int decimals);

// The shortest %g text of v (6 to 17 significant digits) that decimal_number reads back as v
// exactly; "inf", "-inf" and "nan" for those.
std::string decimal_text(double v);

// The words of a refusal of a text that decimal_number did not read, the same in every reader:
// "'TEXT' is not a finite decimal number" (TEXT made printable).
std::string not_a_decimal_number(const std::string& text);

}  // namespace rendulic
