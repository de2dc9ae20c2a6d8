// Command-line options made from the scenario key of an Options table (core/option_table.hpp):
// the option's help is the key's, its default the member's current value (the Options struct's
// own default) and its check the key's range or choices, with the reasons a scenario file
// gets. So `rendulic calibrate --function-tolerance` and calibration.function_tolerance cannot
// drift apart (docs/architecture.md "Options own their defaults and ranges").
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"

namespace rendulic::app {

// The range of a thread count (0: every core), on the command line and from Python.
inline constexpr int kMaxThreads = 4096;

// The words of every option's refusal of a text that is not a number, whichever check meets it
// first (its range, its scenario key's, or the last one of name_words_that_are_not_numbers).
inline std::string not_a_number(const std::string& text) {
  return "Value " + text + " is not a number";
}
inline std::string not_a_whole_number(const std::string& text) {
  return "Value " + text + " is not a whole number (digits only)";
}

// The check of a whole number in [lo, hi], in the words of real_in_range ("Value -1 is out of
// range [0, 4096]"); CLI11's Range said "Value abc not in range 0 to 4096" of a word, and a
// number beyond an int reached the conversion ("Could not convert: --substeps = 3000000000").
inline CLI::Validator integer_in_range(std::int64_t lo, std::int64_t hi) {
  const std::string bounds = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, bounds](std::string& text) -> std::string {
        std::int64_t v = 0;
        if (!CLI::detail::lexical_cast(text, v)) return not_a_whole_number(text);
        if (v < lo || v > hi) return "Value " + text + " is out of range " + bounds;
        return "";
      },
      bounds);
}

// The check of --threads wherever a command runs work: a count, refused in counts. CLI11's
// NonNegativeNumber printed the largest double, 309 digits, as the upper end of its range.
inline CLI::Validator thread_count() { return integer_in_range(0, kMaxThreads); }

// The same check where the count does not come through CLI11 (rendulic.run, rendulic.probe):
// a million threads crashed the interpreter inside the OpenMP runtime.
inline void check_thread_count(int threads) {
  if (threads < 0 || threads > kMaxThreads)
    throw InputError("threads = " + std::to_string(threads) + " is out of range [0, " +
                     std::to_string(kMaxThreads) + "] (0: every core)");
}

// The check of a number that must be positive (zero_allowed: not negative), for options with no
// scenario key behind them; refused on a short line for the same reason as thread_count().
inline CLI::Validator positive_number(bool zero_allowed = false) {
  return CLI::Validator(
      [zero_allowed](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return not_a_number(text);
        if (v > 0.0 || (zero_allowed && v == 0.0)) return "";
        return "Value " + text + (zero_allowed ? " is not a number >= 0" : " is not a number > 0");
      },
      zero_allowed ? "NONNEGATIVE" : "POSITIVE");
}

// The check of a real number in [lo, hi]. CLI11's Range lets NaN through (every comparison with
// it is false), and `bench --friction nan` then skipped the frictional figures without a word;
// it also wrote its bounds as %f ("Value -1 not in range 0.000000 to 10.000000") and called a
// word out of range. The bounds are written as a scenario key's are ("[0, 10]"); `open`: both
// bounds excluded ("(0, 1)").
inline CLI::Validator real_in_range(double lo, double hi, bool open = false) {
  const std::string bounds =
      (open ? "(" : "[") + decimal_g(lo) + ", " + decimal_g(hi) + (open ? ")" : "]");
  return CLI::Validator(
      [lo, hi, open, bounds](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return not_a_number(text);
        if (!std::isfinite(v)) return "Value " + text + " is not a finite number";
        if (open ? !(v > lo && v < hi) : (v < lo || v > hi))
          return "Value " + text + " is out of range " + bounds;
        return "";
      },
      bounds);
}

// The check of a word among `choices`, in a scenario key's words ("'foo' is not one of auto,
// ellipse, line"); CLI11's IsMember said "foo not in {auto,ellipse,line}". The help shows the
// choices (TEXT:{auto, ellipse, line}).
inline CLI::Validator one_of(std::vector<std::string> choices) {
  const std::string shown = "{" + comma_list(choices) + "}";
  return CLI::Validator(
      [choices = std::move(choices)](std::string& text) -> std::string {
        return choice_refusal(text, choices);
      },
      shown);
}

// The check of a file name that must not be empty, for an option whose absence means a
// default: `--params "$P"` with P unset took the law's defaults, `sweep "$S"` the built-in
// scenario, without a word.
inline CLI::Validator file_name() {
  return CLI::Validator(
      [](std::string& text) { return text.empty() ? std::string("the file name is empty") : ""; },
      "FILE");
}

// An empty output folder (`--out "$DIR"` with DIR unset) wrote into the current folder without
// a word; refused on the command line and from Python alike.
inline void refuse_empty_output_folder(const std::string& out) {
  if (out.empty())
    throw InputError("--out: the output folder name is empty (. for the current folder)");
}

// --progress-every of the commands that print progress lines (run, probe).
inline CLI::Option* add_progress_every(CLI::App* app, double& seconds) {
  return app
      ->add_option("--progress-every", seconds,
                   "seconds of work between two progress lines when stderr is not a terminal "
                   "(a log file, a batch job); a terminal gets a live line instead")
      ->check(real_in_range(0.1, 86400.0))
      ->capture_default_str();
}

template <class T>
CLI::Option* add_key_option(CLI::App* app, const std::string& flag, T& member, const KeySpec& key) {
  CLI::Option* o = app->add_option(flag, member, key.help);
  if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string>) {
    o->check(CLI::Validator(
        [key](std::string& text) -> std::string {
          T v{};
          // In the words of the other options (CLI11 said "Could not convert: --flag = abc").
          if (!CLI::detail::lexical_cast(text, v)) {
            if constexpr (std::is_same_v<T, bool>)
              return "Value " + text + " is not true or false";
            else if constexpr (std::is_integral_v<T>)
              return not_a_whole_number(text);
            else
              return not_a_number(text);
          }
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

// Gives every FLOAT and INT option of `app` and its subcommands that has no check of its own
// the words of the others for a text that is not a number ("--amplitude: Value abc is not a
// number"), where CLI11 said "Could not convert: --amplitude = abc". Added last, so an
// option's own check speaks first.
inline void name_words_that_are_not_numbers(CLI::App& app) {
  for (CLI::Option* o : app.get_options()) {
    const std::string type = o->get_type_name();
    const std::string base = type.substr(0, type.find(':'));
    if (base == "FLOAT")
      o->check(CLI::Validator(
          [](std::string& text) -> std::string {
            double v = 0.0;
            return CLI::detail::lexical_cast(text, v) ? "" : not_a_number(text);
          },
          ""));
    else if (base == "INT")
      o->check(CLI::Validator(
          [](std::string& text) -> std::string {
            std::int64_t v = 0;
            return CLI::detail::lexical_cast(text, v) ? "" : not_a_whole_number(text);
          },
          ""));
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    name_words_that_are_not_numbers(*sub);
}

}  // namespace rendulic::app
