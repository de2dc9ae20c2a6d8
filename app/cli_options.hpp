// Command-line options made from the scenario key of an Options table (core/option_table.hpp):
// the option's help is the key's, its default the member's current value (the Options struct's
// own default) and its check the key's range or choices, with the reasons a scenario file
// gets. So `rendulic calibrate --function-tolerance` and calibration.function_tolerance cannot
// drift apart (docs/architecture.md "Options own their defaults and ranges").
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <type_traits>

#include "rendulic/core/option_table.hpp"

namespace rendulic::app {

template <class T>
CLI::Option* add_key_option(CLI::App* app, const std::string& flag, T& member, const KeySpec& key) {
  CLI::Option* o = app->add_option(flag, member, key.help);
  if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string>) {
    o->check(CLI::Validator(
        [key](std::string& text) -> std::string {
          T v{};
          // A text that does not convert is the option's own error (CLI11 says so).
          if (!CLI::detail::lexical_cast(text, v)) return "";
          ScenarioValue value;
          if constexpr (std::is_same_v<T, int>)
            value = std::int64_t{v};
          else
            value = v;
          const std::string why = validate_value(key, value);
          return why.empty() ? why : key.path + ": " + why;
        },
        format_range(key)));
  }
  o->capture_default_str();
  return o;
}

}  // namespace rendulic::app
