// CSV reader of one envelope (docs/fitting.md "The fit command"); see envelope_csv.hpp.
#include "rendulic/probes/envelope_csv.hpp"

#include <algorithm>
#include <cctype>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/text_file.hpp"

namespace rendulic {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  std::string t = s.substr(b, e - b + 1);
  if (t.size() >= 2 && t.front() == '"' && t.back() == '"') t = t.substr(1, t.size() - 2);
  return t;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, separator)) out.push_back(trim(field));
  if (!line.empty() && line.back() == separator) out.emplace_back();
  return out;
}

// The header's separator: a comma, or where it has none a semicolon (what a spreadsheet in a
// decimal-comma locale writes as "CSV") or a tab. Such files were refused with "the header must
// name columns 'x' and 'y' (got 'theta_deg;x;y')".
char separator_of(const std::string& header) {
  if (header.find(',') != std::string::npos) return ',';
  if (header.find(';') != std::string::npos) return ';';
  if (header.find('\t') != std::string::npos) return '\t';
  return ',';
}

}  // namespace

Envelope parse_envelope_csv(const std::string& text, const std::string& name) {
  // A spreadsheet's "CSV UTF-8" starts with a byte-order mark, which made the first column's
  // name "\xEF\xBB\xBFx" and the file "without a column 'x'" (the mark does not show).
  constexpr std::string_view kBom = "\xEF\xBB\xBF";
  std::istringstream in(text.starts_with(kBom) ? text.substr(kBom.size()) : text);
  std::string line;
  int line_no = 0;
  std::vector<std::string> header;
  char separator = ',';
  int ix = -1, iy = -1, it = -1;
  Envelope env;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (header.empty()) separator = separator_of(line);
    const std::vector<std::string> fields = split(line, separator);
    const std::string where = name + ":" + std::to_string(line_no);
    if (header.empty()) {
      // A file of rows alone said "column '0' appears twice" of its first row.
      if (std::ranges::all_of(fields,
                              [](const std::string& f) { return decimal_number(f).has_value(); }))
        throw InputError(where +
                         ": the first line is a row of numbers, not a header naming the "
                         "columns (x,y or theta_deg,x,y)");
      header = fields;
      for (std::size_t k = 0; k < header.size(); ++k) {
        for (std::size_t j = 0; j < k; ++j)
          if (header[j] == header[k] && !header[k].empty())
            throw InputError(where + ": column '" + header[k] + "' appears twice");
        const int kk = static_cast<int>(k);
        if (header[k] == "x") ix = kk;
        if (header[k] == "y") iy = kk;
        if (header[k] == "theta_deg") it = kk;
      }
      if (ix < 0 || iy < 0)
        throw InputError(where + ": the header must name columns 'x' and 'y' (got '" + t + "')");
      // Other columns are ignored by design; one that looks meant for the directions (theta,
      // Theta_deg, theta_rad) was ignored without a word, and the fit ran without them.
      if (it < 0)
        for (const std::string& h : header)
          if (lower(h).starts_with("theta"))
            log::warning(where, ": column '", h,
                         "' is not read; the probe directions' column is theta_deg (degrees)");
      continue;
    }
    if (fields.size() != header.size())
      throw InputError(where + ": expected " + std::to_string(header.size()) + " fields, got " +
                       std::to_string(fields.size()));
    auto number = [&](int col) {
      const std::string& f = fields[static_cast<std::size_t>(col)];
      const std::string& cname = header[static_cast<std::size_t>(col)];
      if (f.empty()) throw InputError(where + ": column '" + cname + "' is empty");
      const std::optional<double> v = decimal_number(f);
      if (!v) {
        // A decimal comma (the same locales' "1,5") is not read as 1.5: numbers take a point.
        std::string pointed = f;
        std::replace(pointed.begin(), pointed.end(), ',', '.');
        const bool comma = separator != ',' && pointed != f && decimal_number(pointed);
        throw InputError(where + ": column '" + cname + "': " + not_a_decimal_number(f) +
                         (comma ? " (a decimal comma: write numbers with a point, " + pointed + ")"
                                : std::string()));
      }
      return *v;
    };
    const double x = number(ix);  // in the file's order: the first bad cell is named
    const double y = number(iy);
    env.response.emplace_back(x, y);
    if (it >= 0) env.theta_deg.push_back(number(it));
  }
  if (header.empty()) throw InputError(name + ": empty file (no header line)");
  if (env.response.empty()) throw InputError(name + ": no data rows after the header");
  return env;
}

Envelope read_envelope_csv(const std::filesystem::path& path) {
  // An envelope of 3600 directions is about half a MiB; 256 MiB leaves room for any other
  // program's many more rows, and refuses a stray huge file before it fills the memory.
  constexpr std::size_t kMaxBytes = std::size_t{256} << 20;
  return parse_envelope_csv(read_input_text(path.string(), "CSV file", kMaxBytes), path.string());
}

}  // namespace rendulic
