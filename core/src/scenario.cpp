// Strict scenario parsing and validation (see scenario.hpp; docs/usage.md).
// The TOML tree is walked against the schema: a table is descended only if some declared key
// lives below it, so an unknown key is reported at its own line with the closest declared
// key as a suggestion. Values are converted once, here; the rest of the code reads typed
// values and never sees TOML.
#include "rendulic/core/scenario.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <stdexcept>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/text_file.hpp"

namespace rendulic {

// A TOML basic string that parses back to exactly `s`: every control character escaped
// (a raw one is not TOML, and a NUL would cut the text short wherever it is stored as a C
// string, as in the results file).
std::string toml_quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04X", static_cast<unsigned>(c));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

namespace {

const char* type_name(KeyType t) {
  switch (t) {
    case KeyType::kBool:
      return "boolean";
    case KeyType::kInt:
      return "integer";
    case KeyType::kDouble:
      return "number";
    case KeyType::kString:
      return "string";
    case KeyType::kDoubleList:
      return "list of numbers";
    case KeyType::kStringList:
      return "list of strings";
  }
  return "?";
}

const char* node_type_name(const toml::node& n) {
  if (n.is_boolean()) return "boolean";
  if (n.is_integer()) return "integer";
  if (n.is_floating_point()) return "number";
  if (n.is_string()) return "string";
  if (n.is_array()) return "array";
  if (n.is_table()) return "table";
  return "date/time";
}

}  // namespace

std::string toml_number(double v) {
  std::string s = decimal_text(v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

namespace {

std::string format_value(const ScenarioValue& v) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(std::int64_t i) const { return std::to_string(i); }
    std::string operator()(double d) const { return toml_number(d); }
    std::string operator()(const std::string& s) const { return toml_quoted(s); }
    std::string operator()(const std::vector<double>& xs) const {
      std::string out = "[";
      for (std::size_t i = 0; i < xs.size(); ++i) out += (i ? ", " : "") + toml_number(xs[i]);
      return out + "]";
    }
    std::string operator()(const std::vector<std::string>& xs) const {
      std::string out = "[";
      for (std::size_t i = 0; i < xs.size(); ++i) out += (i ? ", " : "") + toml_quoted(xs[i]);
      return out + "]";
    }
  };
  return std::visit(Visitor{}, v);
}

}  // namespace

std::string format_range(const KeySpec& s) {
  if (!s.choices.empty()) {
    return "one of " + comma_list(s.choices);
  }
  if (s.type == KeyType::kBool || s.type == KeyType::kString) return "";
  const bool lo = std::isfinite(s.min), hi = std::isfinite(s.max);
  if (!lo && !hi) return "";
  std::string out;
  out += lo ? (s.min_open ? "(" : "[") : "(";
  auto num = [&](double x) {
    return s.type == KeyType::kInt ? std::to_string(static_cast<long long>(x)) : toml_number(x);
  };
  out += lo ? num(s.min) : std::string("-inf");
  out += ", ";
  out += hi ? num(s.max) : std::string("inf");
  out += hi ? (s.max_open ? ")" : "]") : ")";
  return out;
}

namespace {

// Range check of one number; returns the reason or "".
std::string check_number(const KeySpec& s, double x) {
  if (!std::isfinite(x)) return "must be a finite number, got " + toml_number(x);
  const bool below = s.min_open ? !(x > s.min) : x < s.min;
  const bool above = s.max_open ? !(x < s.max) : x > s.max;
  if (below || above) return "value " + toml_number(x) + " is out of range " + format_range(s);
  return "";
}

// Range check of one integer, in integers: compared in double, 4e18 + 1 would pass a bound of
// 4e18, and 2^63 - 1 would print as another number.
std::string check_int(const KeySpec& s, std::int64_t x) {
  constexpr double kLimit = 9.2e18;  // below 2^63: bounds beyond it bound nothing
  bool below = false, above = false;
  if (std::isfinite(s.min) && s.min > -kLimit) {
    const auto lo = static_cast<std::int64_t>(s.min_open ? std::floor(s.min) : std::ceil(s.min));
    below = s.min_open ? x <= lo : x < lo;
  }
  if (std::isfinite(s.max) && s.max < kLimit) {
    const auto hi = static_cast<std::int64_t>(s.max_open ? std::ceil(s.max) : std::floor(s.max));
    above = s.max_open ? x >= hi : x > hi;
  }
  if (below || above) return "value " + std::to_string(x) + " is out of range " + format_range(s);
  return "";
}

// Where `text` stops being UTF-8 (TOML text is UTF-8; a --set value need not be), or npos.
std::size_t invalid_utf8_at(const std::string& text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned c = p[i];
    std::size_t len = c < 0x80           ? 1
                      : (c >> 5) == 0x6  ? 2
                      : (c >> 4) == 0xe  ? 3
                      : (c >> 3) == 0x1e ? 4
                                         : 0;
    if (len == 0 || i + len > n) return i;
    unsigned cp = len == 1 ? c : c & (0x7f >> len);
    for (std::size_t k = 1; k < len; ++k) {
      if ((p[i + k] & 0xc0) != 0x80) return i;
      cp = (cp << 6) | (p[i + k] & 0x3f);
    }
    const unsigned min_cp[] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < min_cp[len] || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return i;
    i += len;
  }
  return std::string::npos;
}

std::string check_choice(const KeySpec& s, const std::string& x) {
  if (const auto at = invalid_utf8_at(x); at != std::string::npos)
    return "the text is not valid UTF-8 (byte " + std::to_string(at) + ")";
  // The word is valid UTF-8 here but may hold control characters: the refusal shows it
  // printable (a choice never holds one, so the check is the same).
  return s.choices.empty() ? "" : choice_refusal(printable(x), s.choices);
}

// Validates a value against its spec; returns the reason or "".
std::string validate(const KeySpec& s, const ScenarioValue& v) {
  switch (s.type) {
    case KeyType::kBool:
      return "";
    case KeyType::kInt:
      return check_int(s, std::get<std::int64_t>(v));
    case KeyType::kDouble:
      return check_number(s, std::get<double>(v));
    case KeyType::kString:
      return check_choice(s, std::get<std::string>(v));
    case KeyType::kDoubleList: {
      const auto& xs = std::get<std::vector<double>>(v);
      if (xs.size() < s.min_size || xs.size() > s.max_size)
        return "list has " + std::to_string(xs.size()) + " entries, allowed " +
               std::to_string(s.min_size) + ".." +
               (s.max_size == std::numeric_limits<std::size_t>::max() ? std::string("any")
                                                                      : std::to_string(s.max_size));
      for (double x : xs)
        if (auto r = check_number(s, x); !r.empty()) return r;
      if (s.distinct)
        for (std::size_t i = 0; i < xs.size(); ++i)
          for (std::size_t j = 0; j < i; ++j)
            if (paths::group_number(xs[j]) == paths::group_number(xs[i]))
              return "value " + toml_number(xs[i]) + " given twice" +
                     (xs[j] == xs[i] ? std::string()
                                     : " (as " + toml_number(xs[j]) +
                                           ": entries are told apart by 6 significant digits, "
                                           "the names of their groups)");
      return "";
    }
    case KeyType::kStringList: {
      const auto& xs = std::get<std::vector<std::string>>(v);
      if (xs.size() < s.min_size || xs.size() > s.max_size)
        return "list has " + std::to_string(xs.size()) + " entries, allowed at least " +
               std::to_string(s.min_size);
      for (const auto& x : xs)
        if (auto r = check_choice(s, x); !r.empty()) return r;
      if (s.distinct)
        if (const std::string* again = first_repeat(xs))
          return "value '" + *again + "' given twice";
      return "";
    }
  }
  return "";
}

// The value type a spec expects; std::nullopt-like failure is reported as a reason string.
bool holds_type(const KeySpec& s, const ScenarioValue& v) {
  switch (s.type) {
    case KeyType::kBool:
      return std::holds_alternative<bool>(v);
    case KeyType::kInt:
      return std::holds_alternative<std::int64_t>(v);
    case KeyType::kDouble:
      return std::holds_alternative<double>(v);
    case KeyType::kString:
      return std::holds_alternative<std::string>(v);
    case KeyType::kDoubleList:
      return std::holds_alternative<std::vector<double>>(v);
    case KeyType::kStringList:
      return std::holds_alternative<std::vector<std::string>>(v);
  }
  return false;
}

// TOML node -> typed value. Integers are accepted where numbers are expected (TOML writes
// 9261 and 9261.0 differently; a user means the same). Throws std::string on a type mismatch.
ScenarioValue convert(const KeySpec& s, const toml::node& n) {
  auto article = [](const char* w) { return std::strchr("aeiou", w[0]) ? "an " : "a "; };
  const std::string want = std::string("expected ") + article(type_name(s.type)) +
                           type_name(s.type) + ", got " + article(node_type_name(n)) +
                           node_type_name(n);
  switch (s.type) {
    case KeyType::kBool:
      if (auto b = n.as_boolean()) return b->get();
      throw want;
    case KeyType::kInt:
      if (auto i = n.as_integer()) return i->get();
      throw want;
    case KeyType::kDouble:
      if (auto i = n.as_integer()) return static_cast<double>(i->get());
      if (auto d = n.as_floating_point()) return d->get();
      throw want;
    case KeyType::kString:
      if (auto str = n.as_string()) return str->get();
      throw want;
    case KeyType::kDoubleList: {
      auto arr = n.as_array();
      if (!arr) throw want;
      std::vector<double> xs;
      for (const auto& e : *arr) {
        if (auto i = e.as_integer())
          xs.push_back(static_cast<double>(i->get()));
        else if (auto d = e.as_floating_point())
          xs.push_back(d->get());
        else
          throw std::string("expected a list of numbers, found ") + article(node_type_name(e)) +
              node_type_name(e);
      }
      return xs;
    }
    case KeyType::kStringList: {
      auto arr = n.as_array();
      if (!arr) throw want;
      std::vector<std::string> xs;
      for (const auto& e : *arr) {
        if (auto str = e.as_string())
          xs.push_back(str->get());
        else
          throw std::string("expected a list of strings, found ") + article(node_type_name(e)) +
              node_type_name(e);
      }
      return xs;
    }
  }
  throw want;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string section_of(const std::string& path) {
  auto dot = path.rfind('.');
  return dot == std::string::npos ? std::string{} : path.substr(0, dot);
}

// toml++ builds a dotted key a.b.c... by recursion, one level per segment, so a key of
// 50,000 segments overflows the stack before any check of ours runs. No scenario key has more
// than a few segments: a chain of more than kMaxKeyDots dots between key segments is refused
// first. The scan treats quoted strings and bare words as segments and skips comments; in a
// valid value only a number (1.5) or a time (07:32:00.999) joins two words by a dot.
void check_key_depth(std::string_view t, const std::string& source_name) {
  constexpr int kMaxKeyDots = 16;
  int dots = 0, line = 1;
  bool after_segment = false, after_dot = false;
  auto bare = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  };
  for (std::size_t i = 0; i < t.size();) {
    const char c = t[i];
    if (c == '#') {  // comment: to the end of the line
      while (i < t.size() && t[i] != '\n') ++i;
      continue;
    }
    if (c == '"' || c == '\'' || bare(c)) {  // one segment
      if (!after_dot) dots = 0;
      if (bare(c)) {
        while (i < t.size() && bare(t[i])) ++i;
      } else {
        const bool multi = t.substr(i, 3) == std::string(3, c);
        const std::string close = multi ? std::string(3, c) : std::string(1, c);
        i += close.size();
        while (i < t.size() && t.substr(i, close.size()) != close) {
          if (t[i] == '\n') ++line;
          if (c == '"' && t[i] == '\\') ++i;  // escaped character
          if (!multi && i < t.size() && t[i] == '\n') break;
          ++i;
        }
        i += close.size();
      }
      after_segment = true, after_dot = false;
      continue;
    }
    if (c == '.' && after_segment) {
      if (++dots > kMaxKeyDots)
        throw InputError(source_name + ":" + std::to_string(line) +
                         ": a dotted key nested deeper than " + std::to_string(kMaxKeyDots) +
                         " levels (scenario keys have two: section.key)");
      after_segment = false, after_dot = true;
      ++i;
      continue;
    }
    if (c == ' ' || c == '\t') {  // allowed around the dots of a key
      ++i;
      continue;
    }
    if (c == '\n') ++line;
    dots = 0, after_segment = false, after_dot = false;
    ++i;
  }
}

}  // namespace

const std::string* first_repeat(const std::vector<std::string>& names) {
  for (auto n = names.begin(); n != names.end(); ++n)
    if (std::find(names.begin(), n, *n) != n) return &*n;
  return nullptr;
}

std::string validate_value(const KeySpec& spec, const ScenarioValue& value) {
  return validate(spec, value);
}

ScenarioSchema& ScenarioSchema::add(KeySpec spec) {
  if (find(spec.path)) throw std::logic_error("scenario key declared twice: " + spec.path);
  if (!holds_type(spec, spec.default_value))
    throw std::logic_error("scenario key " + spec.path + ": default has the wrong type");
  if (auto r = validate(spec, spec.default_value); !r.empty())
    throw std::logic_error("scenario key " + spec.path + ": default " + r);
  keys_.push_back(std::move(spec));
  return *this;
}

const KeySpec* ScenarioSchema::find(std::string_view path) const {
  for (const auto& k : keys_)
    if (k.path == path) return &k;
  return nullptr;
}

std::string ScenarioSchema::suggest(std::string_view path) const {
  std::string best;
  std::size_t best_d = std::max<std::size_t>(2, path.size() / 4) + 1;
  for (const auto& k : keys_) {
    const std::size_t d = edit_distance(path, k.path);
    if (d < best_d) best_d = d, best = k.path;
  }
  if (!best.empty()) return best;
  // Same leaf name in another section: a key put in the wrong table.
  const auto leaf =
      path.substr(path.rfind('.') == std::string_view::npos ? 0 : path.rfind('.') + 1);
  for (const auto& k : keys_)
    if (k.path.size() > leaf.size() && k.path.ends_with("." + std::string(leaf))) return k.path;
  return "";
}

std::string ScenarioSchema::markdown() const {
  // One table per section, in the order the sections first appear: keys of one section are
  // registered by more than one Options struct (run.description after report.*).
  const auto section = [](const KeySpec& k) {
    const auto dot = k.path.find('.');
    return dot == std::string::npos ? std::string("(top level)") : k.path.substr(0, dot);
  };
  std::vector<std::string> sections;
  for (const auto& k : keys_)
    if (std::find(sections.begin(), sections.end(), section(k)) == sections.end())
      sections.push_back(section(k));
  std::ostringstream out;
  for (const auto& top : sections) {
    out << "\n## [" << top << "]\n\n"
        << "| key | type | unit | default | range | meaning |\n"
        << "|---|---|---|---|---|---|\n";
    for (const auto& k : keys_) {
      if (section(k) != top) continue;
      std::string help = k.help;
      std::replace(help.begin(), help.end(), '|', '/');
      std::string range = format_range(k);
      if (k.distinct) range += range.empty() ? "distinct" : ", distinct";
      out << "| `" << k.path << "` | " << type_name(k.type) << " | " << k.unit << " | `"
          << format_value(k.default_value) << "` | " << range << " | " << help << " |\n";
    }
  }
  return out.str();
}

Scenario::Scenario(const ScenarioSchema& schema) : schema_(&schema) {
  for (const auto& k : schema.keys()) {
    values_[k.path] = k.default_value;
    origins_[k.path] = "default";
  }
}

Scenario Scenario::from_file(const std::string& path, const ScenarioSchema& schema) {
  constexpr std::size_t kMaxBytes = std::size_t{1} << 20;  // scenarios are a few kB
  return from_string(read_input_text(path, "scenario file", kMaxBytes), path, schema);
}

Scenario Scenario::from_string(std::string_view text, const std::string& source_name,
                               const ScenarioSchema& schema) {
  Scenario sc(schema);
  sc.source_name_ = source_name;
  check_key_depth(text, source_name);
  toml::table root;
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    throw InputError(source_name + ":" + std::to_string(e.source().begin.line) +
                     ": TOML syntax error: " + std::string(e.description()));
  }
  auto where = [&](const toml::source_region& r) {
    return source_name + ":" + std::to_string(r.begin.line);
  };
  auto has_below = [&](const std::string& prefix) {
    for (const auto& k : schema.keys())
      if (k.path.starts_with(prefix + ".")) return true;
    return false;
  };
  // Recursive walk; std::function would be fine, a local struct keeps it allocation-free.
  struct Walker {
    Scenario& sc;
    const ScenarioSchema& schema;
    decltype(where)& where_fn;
    decltype(has_below)& below_fn;
    void walk(const toml::table& t, const std::string& prefix) {
      for (auto&& [key, node] : t) {
        const std::string path =
            prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
        const toml::source_region& loc = node.source().begin.line ? node.source() : key.source();
        if (const KeySpec* spec = schema.find(path)) {
          ScenarioValue v;
          try {
            v = convert(*spec, node);
          } catch (const std::string& why) {
            throw InputError(where_fn(loc) + ": key '" + path + "': " + why);
          }
          if (auto r = validate(*spec, v); !r.empty())
            throw InputError(where_fn(loc) + ": key '" + path + "': " + r);
          sc.values_[path] = std::move(v);
          sc.origins_[path] = where_fn(loc);
        } else if (node.is_table() && below_fn(path)) {
          walk(*node.as_table(), path);
        } else {
          const std::string hint = schema.suggest(path);
          throw InputError(where_fn(key.source()) + ": unknown key '" + path + "'" +
                           (hint.empty() ? std::string(" (see rendulic keys)")
                                         : " (did you mean '" + hint + "'?)"));
        }
      }
    }
  } walker{sc, schema, where, has_below};
  walker.walk(root, "");
  return sc;
}

void Scenario::apply_override(std::string_view assignment) {
  const std::string what = "--set " + std::string(assignment);
  const auto eq = assignment.find('=');
  if (eq == std::string_view::npos || eq == 0) throw InputError(what + ": expected key=value");
  auto trim = [](std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return std::string(s);
  };
  const std::string key = trim(assignment.substr(0, eq));
  const std::string text = trim(assignment.substr(eq + 1));
  const KeySpec* spec = schema_->find(key);
  if (!spec) {
    const std::string hint = schema_->suggest(key);
    throw InputError(what + ": unknown key '" + key + "'" +
                     (hint.empty() ? std::string{} : " (did you mean '" + hint + "'?)"));
  }
  ScenarioValue v;
  try {
    toml::table t = toml::parse("v = " + text);
    v = convert(*spec, *t.get("v"));
  } catch (const toml::parse_error&) {
    // Bare words are what a shell user types for strings: accept them where a string is due.
    if (spec->type == KeyType::kString) {
      v = text;
    } else if (spec->type == KeyType::kStringList) {
      std::vector<std::string> xs;
      // [a,b] as a shell user types it (TOML wants ["a","b"]): the brackets enclose the list.
      std::string_view inner = text;
      if (inner.size() >= 2 && inner.front() == '[' && inner.back() == ']')
        inner = inner.substr(1, inner.size() - 2);
      std::stringstream ss{std::string(inner)};
      for (std::string item; std::getline(ss, item, ',');) xs.push_back(trim(item));
      v = xs;
    } else {
      throw InputError(what + ": key '" + key + "': '" + text + "' is not a valid " +
                       type_name(spec->type));  // e.g. "not a valid number"
    }
  } catch (const std::string& why) {
    throw InputError(what + ": key '" + key + "': " + why);
  }
  if (auto r = validate(*spec, v); !r.empty()) throw InputError(what + ": key '" + key + "': " + r);
  values_[key] = std::move(v);
  origins_[key] = "--set";
}

void Scenario::set(std::string_view path, const ScenarioValue& value) {
  const KeySpec& s = spec(path);
  if (!holds_type(s, value))
    throw InputError("key '" + s.path + "': expected a " + type_name(s.type));
  if (auto r = validate(s, value); !r.empty()) throw InputError("key '" + s.path + "': " + r);
  values_[s.path] = value;
  origins_[s.path] = "api";
}

const KeySpec& Scenario::spec(std::string_view path) const {
  const KeySpec* s = schema_->find(path);
  if (!s) throw std::logic_error("scenario key not declared: " + std::string(path));
  return *s;
}

const ScenarioValue& Scenario::value(std::string_view path) const {
  spec(path);
  return values_.find(path)->second;
}

bool Scenario::get_bool(std::string_view p) const { return std::get<bool>(value(p)); }
std::int64_t Scenario::get_int(std::string_view p) const {
  return std::get<std::int64_t>(value(p));
}
double Scenario::get_double(std::string_view p) const { return std::get<double>(value(p)); }
const std::string& Scenario::get_string(std::string_view p) const {
  return std::get<std::string>(value(p));
}
const std::vector<double>& Scenario::get_doubles(std::string_view p) const {
  return std::get<std::vector<double>>(value(p));
}
const std::vector<std::string>& Scenario::get_strings(std::string_view p) const {
  return std::get<std::vector<std::string>>(value(p));
}
bool Scenario::is_set(std::string_view p) const { return origin(p) != "default"; }
std::string Scenario::origin(std::string_view p) const {
  spec(p);
  return origins_.find(p)->second;
}

namespace {
// "section.key" -> value text of every setting line of to_toml()'s text, in key order.
std::map<std::string, std::string> settings_of(const std::string& toml_text) {
  std::map<std::string, std::string> out;
  std::istringstream in(toml_text);
  std::string line, section;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (line[0] == '[' && line.back() == ']') {
      section = line.substr(1, line.size() - 2);
      continue;
    }
    const std::size_t eq = line.find(" = ");
    if (eq == std::string::npos) continue;
    out[(section.empty() ? "" : section + ".") + line.substr(0, eq)] = line.substr(eq + 3);
  }
  return out;
}
}  // namespace

std::vector<Scenario::Difference> Scenario::differences_from(const std::string& stored_toml) const {
  const auto stored = settings_of(stored_toml), now = settings_of(to_toml());
  std::vector<Difference> out;
  const std::string absent = "(absent)";
  for (const auto& [key, value] : stored) {
    const auto it = now.find(key);
    if (it == now.end())
      out.push_back({key, value, absent});
    else if (it->second != value)
      out.push_back({key, value, it->second});
  }
  for (const auto& [key, value] : now)
    if (!stored.count(key)) out.push_back({key, absent, value});
  std::sort(out.begin(), out.end(),
            [](const Difference& a, const Difference& b) { return a.key < b.key; });
  return out;
}

std::string Scenario::to_toml() const {
  std::ostringstream out;
  out << "# effective scenario (defaults + " << source_name_ << " + overrides)\n";
  // Keys without a section must precede the first table header.
  for (const auto& k : schema_->keys())
    if (section_of(k.path).empty()) out << k.path << " = " << format_value(value(k.path)) << "\n";
  std::vector<std::string> sections;
  for (const auto& k : schema_->keys()) {
    const std::string s = section_of(k.path);
    if (!s.empty() && std::find(sections.begin(), sections.end(), s) == sections.end())
      sections.push_back(s);
  }
  for (const auto& s : sections) {
    out << "\n[" << s << "]\n";
    for (const auto& k : schema_->keys())
      if (section_of(k.path) == s)
        out << k.path.substr(s.size() + 1) << " = " << format_value(value(k.path)) << "\n";
  }
  return out.str();
}

}  // namespace rendulic
