// A list of names in a message, a log line or a report, written one way ("a, b, c"); with a
// limit, the first `shown` and "and N more", so that a file of thousands of states does not
// make a message of thousands of words. And the refusal of a word outside a list of choices,
// also written one way (docs/architecture.md "Where each concept lives").
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <string_view>

namespace rendulic {

// "a, b, c" of any range of texts (std::string, const char*, std::string_view); `empty` if the
// range is. Beyond `shown` items: "a, b and 3 more" followed by `more_hint`.
template <class Range>
std::string comma_list(const Range& items, std::string_view empty = "",
                       std::size_t shown = std::numeric_limits<std::size_t>::max(),
                       std::string_view more_hint = "") {
  std::string out;
  std::size_t n = 0;
  for (const auto& item : items) {
    if (n < shown) {
      if (n) out += ", ";
      out += std::string_view(item);
    }
    ++n;
  }
  if (n == 0) return std::string(empty);
  if (n > shown) out += " and " + std::to_string(n - shown) + " more" + std::string(more_hint);
  return out;
}

// The refusal of `word` that is not among `choices`: "'foo' is not one of a, b, c". Scenario
// keys, option choices, probe methods, path types and model arguments all say it so.
template <class Range>
std::string not_one_of(std::string_view word, const Range& choices) {
  // Appended rather than "'" + word + ...: GCC 12 warns of a false overlap (-Wrestrict) there.
  std::string out = "'";
  out += word;
  out += "' is not one of ";
  out += comma_list(choices);
  return out;
}

// "" when `word` is among `choices`, else not_one_of's refusal: the one check behind a scenario
// key's choices, an option's choices, the probe methods, the path types and the Python
// module's choices.
template <class Range>
std::string choice_refusal(std::string_view word, const Range& choices) {
  for (const auto& c : choices)
    if (std::string_view(c) == word) return "";
  return not_one_of(word, choices);
}

}  // namespace rendulic
