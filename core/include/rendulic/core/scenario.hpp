// Strict scenario files (TOML, toml++) and `--set` overrides (docs/usage.md).
// Every key a scenario may hold is declared once in a ScenarioSchema (type, unit, default,
// range, help): modules register their own keys (e.g. dem::register_scenario_keys), the app
// combines them. An unknown key, a wrong type or a value out of range is an InputError whose
// one line names the key and where it came from ("quick.toml:12", "--set"), so that the CLI
// can exit 2 before anything is written. The effective scenario (defaults + file + overrides)
// serialises back to TOML for the results file.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace rendulic {

enum class KeyType { kBool, kInt, kDouble, kString, kDoubleList, kStringList };

using ScenarioValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>,
                                   std::vector<std::string>>;

struct KeySpec {
  std::string path;  // dotted path, e.g. "preparation.nu0"
  KeyType type = KeyType::kDouble;
  ScenarioValue default_value;
  std::string unit;  // "-" for dimensionless
  std::string help;  // one sentence
  // Numeric range for numbers and the elements of numeric lists (inclusive unless *_open).
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  bool max_open = false;
  std::vector<std::string> choices;  // allowed strings (kString, kStringList); empty = any
  std::size_t min_size = 0;          // list length bounds
  std::size_t max_size = std::numeric_limits<std::size_t>::max();
  // List entries must differ: each names a group or a piece of work. Numbers are told apart
  // by their text in a group's name (paths::group_number, 6 significant digits): 1e-4 and
  // 1.000001e-4 would write one envelope group twice.
  bool distinct = false;
};

// A TOML basic string (quotes included) that parses back to exactly `s`, control characters
// escaped: for values, and for keys that are not bare (Python's parameter dictionaries).
std::string toml_quoted(const std::string& s);
// A TOML float that parses back to exactly `v` (decimal_text, ".0" added to an integer's
// digits; inf and nan as TOML spells them, which the scenario's checks refuse).
std::string toml_number(double v);

class ScenarioSchema {
 public:
  // Declares a key; a duplicate path or a default that violates its own range is a bug and
  // throws std::logic_error.
  ScenarioSchema& add(KeySpec spec);
  const KeySpec* find(std::string_view path) const;
  const std::vector<KeySpec>& keys() const { return keys_; }
  // The closest declared key to a mistyped one (edit distance), or "" if none is close.
  std::string suggest(std::string_view path) const;
  // Markdown reference: one table per top-level section, every key with unit, default, range.
  std::string markdown() const;

 private:
  std::vector<KeySpec> keys_;
};

class Scenario {
 public:
  // Every key at its default.
  explicit Scenario(const ScenarioSchema& schema);
  // Parses and validates a TOML file / text; throws InputError "FILE:LINE: key 'a.b': reason".
  static Scenario from_file(const std::string& path, const ScenarioSchema& schema);
  static Scenario from_string(std::string_view text, const std::string& source_name,
                              const ScenarioSchema& schema);
  // "a.b=value" with value in TOML syntax (strings may be bare); same validation, the error
  // names "--set a.b".
  void apply_override(std::string_view assignment);

  bool get_bool(std::string_view path) const;
  std::int64_t get_int(std::string_view path) const;
  double get_double(std::string_view path) const;
  const std::string& get_string(std::string_view path) const;
  const std::vector<double>& get_doubles(std::string_view path) const;
  const std::vector<std::string>& get_strings(std::string_view path) const;
  // True where the value came from the file or an override rather than the default.
  bool is_set(std::string_view path) const;
  // "FILE:LINE", "--set" or "default".
  std::string origin(std::string_view path) const;
  // Sets a value programmatically with the same validation (origin "api").
  void set(std::string_view path, const ScenarioValue& value);

  // The effective scenario, every key, as TOML text that parses back to the same values.
  std::string to_toml() const;
  // The settings in which an effective scenario stored by to_toml() (a results file's
  // /@scenario) differs from this one, in key order; empty for the same run. Its first line, the
  // scenario file's name as it was given, is not a setting: the same file by another path (or a
  // copy of it) is the same scenario.
  struct Difference {
    std::string key, stored, now;  // stored/now: the value's text, "(absent)" where there is none
  };
  std::vector<Difference> differences_from(const std::string& stored_toml) const;
  const std::string& source_name() const { return source_name_; }
  const ScenarioSchema& schema() const { return *schema_; }

 private:
  const KeySpec& spec(std::string_view path) const;
  const ScenarioValue& value(std::string_view path) const;

  const ScenarioSchema* schema_;
  std::string source_name_ = "defaults";
  std::map<std::string, ScenarioValue, std::less<>> values_;
  std::map<std::string, std::string, std::less<>> origins_;
};

}  // namespace rendulic
