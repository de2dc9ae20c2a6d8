// One table per Options struct: its scenario keys, each with the member it sets
// (docs/architecture.md "Options own their defaults and ranges"). The struct's in-class
// initialisers are the defaults and the table's KeySpec the unit, range and help, so that the
// scenario schema, the struct's own IsValid and a command line (app/cli_options.hpp) all read
// the same numbers: registering a table puts default = Options{}'s member into the schema,
// reading a scenario fills the members, and check() holds a struct built in code (a test, the
// sweep) to the ranges a scenario file is held to, with the same reasons.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "rendulic/core/scenario.hpp"

namespace rendulic {

// Why `value` is not allowed by `spec` (range, choices, list size), or "" if it is.
std::string validate_value(const KeySpec& spec, const ScenarioValue& value);
// The spec's range as a scenario error states it: "[1e-16, 0.1]", "(0, inf)", "one of a, b".
std::string format_range(const KeySpec& spec);
// The first entry of `names` that repeats an earlier one, or nullptr: the check behind "given
// twice" of a distinct list of names (KeySpec::distinct), probe's --methods, sweep's --factors.
const std::string* first_repeat(const std::vector<std::string>& names);

template <class Options>
struct OptionRow {
  template <class T>
  using Member = T& (*)(Options&);
  using Access = std::variant<Member<bool>, Member<int>, Member<std::int64_t>, Member<std::size_t>,
                              Member<double>, Member<std::string>, Member<std::vector<double>>,
                              Member<std::vector<std::string>>>;
  // Path, unit, help and range; type and default_value are filled from the member.
  KeySpec key;
  Access member;
};

template <class Options>
class OptionTable {
 public:
  using Row = OptionRow<Options>;
  explicit OptionTable(std::vector<Row> rows) : rows_(std::move(rows)) {
    const Options defaults{};
    for (Row& r : rows_) r.key = filled(r, defaults);
  }

  const std::vector<Row>& rows() const { return rows_; }
  // The key of a row by its path (a std::logic_error for a path the table does not have).
  const KeySpec& key(const std::string& path) const {
    for (const Row& r : rows_)
      if (r.key.path == path) return r.key;
    throw std::logic_error("option table: no key " + path);
  }
  void register_keys(ScenarioSchema& schema) const {
    for (const Row& r : rows_) schema.add(r.key);
  }
  // The members from the scenario (already validated against these keys).
  void read(const Scenario& scenario, Options& o) const {
    for (const Row& r : rows_) {
      const std::string& p = r.key.path;
      std::visit(
          [&](auto member) {
            auto& m = member(o);
            using T = std::decay_t<decltype(m)>;
            if constexpr (std::is_same_v<T, bool>)
              m = scenario.get_bool(p);
            else if constexpr (std::is_same_v<T, int>)
              m = static_cast<int>(scenario.get_int(p));
            else if constexpr (std::is_same_v<T, std::int64_t>)
              m = scenario.get_int(p);
            else if constexpr (std::is_same_v<T, std::size_t>)  // the key's range is >= 0
              m = static_cast<std::size_t>(scenario.get_int(p));
            else if constexpr (std::is_same_v<T, double>)
              m = scenario.get_double(p);
            else if constexpr (std::is_same_v<T, std::string>)
              m = scenario.get_string(p);
            else if constexpr (std::is_same_v<T, std::vector<double>>)
              m = scenario.get_doubles(p);
            else
              m = scenario.get_strings(p);
          },
          r.member);
    }
  }
  // The first member outside its key's range: "probes.dt_factor: value -1 is out of range
  // [0, inf)" in *why, false. True if every member is allowed.
  bool check(const Options& o, std::string* why) const {
    for (const Row& r : rows_) {
      const std::string reason = validate_value(r.key, value_of(r, o));
      if (!reason.empty()) {
        if (why) *why = r.key.path + ": " + reason;
        return false;
      }
    }
    return true;
  }

 private:
  static ScenarioValue value_of(const Row& r, const Options& o) {
    Options& m = const_cast<Options&>(o);  // the accessors only read here
    return std::visit(
        [&](auto member) -> ScenarioValue {
          const auto& v = member(m);
          using T = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<T, int>)
            return std::int64_t{v};
          else if constexpr (std::is_same_v<T, std::size_t>)
            return static_cast<std::int64_t>(v);
          else
            return v;
        },
        r.member);
  }
  static KeySpec filled(const Row& r, const Options& defaults) {
    KeySpec k = r.key;
    k.default_value = value_of(r, defaults);
    k.type = std::visit(
        [](auto member) {
          using T = std::decay_t<decltype(member(std::declval<Options&>()))>;
          if constexpr (std::is_same_v<T, bool>)
            return KeyType::kBool;
          else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, std::int64_t> ||
                             std::is_same_v<T, std::size_t>)
            return KeyType::kInt;
          else if constexpr (std::is_same_v<T, double>)
            return KeyType::kDouble;
          else if constexpr (std::is_same_v<T, std::string>)
            return KeyType::kString;
          else if constexpr (std::is_same_v<T, std::vector<double>>)
            return KeyType::kDoubleList;
          else
            return KeyType::kStringList;
        },
        r.member);
    return k;
  }

  std::vector<Row> rows_;
};

}  // namespace rendulic
