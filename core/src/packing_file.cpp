// Readers and the writer of packing files (see packing_file.hpp; docs/interop.md). The LAMMPS
// formats are read by their documented layout (LAMMPS manual: read_data, dump custom), line by
// line, with strict numbers: a field that is not wholly a finite number is an error naming the
// file and the line, never a zero or a NaN carried on.
#include "rendulic/core/packing_file.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <map>
#include <numbers>
#include <numeric>
#include <sstream>
#include <string_view>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/text_file.hpp"

namespace rendulic {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> split_words(const std::string& line) {
  std::vector<std::string> w;
  std::istringstream in(line);
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

// The text of a line before its comment ('#').
std::string strip_comment(const std::string& line) { return line.substr(0, line.find('#')); }

// A line reader that knows where it is, for the messages.
class Lines {
 public:
  explicit Lines(const fs::path& file) : file_(file), in_(file) {
    if (!in_) throw InputError(file.string() + ": cannot open the packing file");
  }
  bool next(std::string& line) {
    if (!std::getline(in_, line)) return false;
    ++number_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }
  // The next line, which the format requires: a file that ends before it is refused, naming
  // what is missing (the line before it was read as that line).
  void need(std::string& line, const std::string& what) {
    if (!next(line)) fail("the file ends before " + what);
  }
  // The next line, which must start with `item` (a dump's "ITEM: ..." keyword).
  void need_item(std::string& line, const char* item) {
    need(line, std::string("'") + item + "'");
    if (line.rfind(item, 0) != 0) fail(std::string("expected '") + item + "'");
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(file_.string() + ":" + std::to_string(number_) + ": " + printable(why));
  }
  double number(const std::string& text, const char* what) const {
    const std::optional<double> v = decimal_number(text);
    if (!v) fail(std::string(what) + " " + not_a_decimal_number(text));
    return *v;
  }
  long long integer(const std::string& text, const char* what) const {
    errno = 0;
    char* end = nullptr;
    const long long v = std::strtoll(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || errno == ERANGE)
      fail(std::string(what) + " '" + text + "' is not an integer");
    return v;
  }
  const fs::path& file() const { return file_; }

 private:
  fs::path file_;
  std::ifstream in_;
  long number_ = 0;
};

void check_box(const Lines& at, double lo, double hi, const char* axis) {
  if (!(hi > lo))
    at.fail(std::string("degenerate box: ") + axis + "hi <= " + axis + "lo (" + decimal_g(hi) +
            " <= " + decimal_g(lo) + ")");
}

double wrap(double x, double L) {
  double q = x - L * std::floor(x / L);
  return q >= L ? 0.0 : q;  // a value a hair below 0 rounds onto L
}

// Orders the rows by atom id (files list atoms in any order), refusing duplicates.
std::vector<std::size_t> order_by_id(const std::vector<long long>& ids, const fs::path& file) {
  std::vector<std::size_t> order(ids.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return ids[a] < ids[b]; });
  for (std::size_t k = 1; k < order.size(); ++k)
    if (ids[order[k]] == ids[order[k - 1]])
      throw InputError(file.string() + ": atom id " + std::to_string(ids[order[k]]) +
                       " appears twice");
  return order;
}

// Shared checks of every reader: a packing rendulic can hold (the engine then checks that the
// particles fit the cell).
void check_packing(const Packing& p) {
  if (p.size() == 0) throw InputError(p.origin + ": no particles");
  for (int a = 0; a < 3; ++a)
    if (!(p.lengths[a] > 0) || !std::isfinite(p.lengths[a]))
      throw InputError(p.origin + ": the box length along axis " + std::to_string(a) +
                       " is not a positive finite number");
  // Each length finite is not enough: 1e300 m on every axis makes the volume, and with it the
  // volume fraction and the pair search's cell widths, inf and NaN.
  if (!std::isfinite(p.lengths.prod()) || !(p.lengths.prod() > 0))
    throw InputError(
        p.origin + ": the box volume (the product of its lengths) is not a positive finite number");
  if (!p.positions.allFinite()) throw InputError(p.origin + ": a position is not finite");
  if (p.velocities.rows() > 0 && !p.velocities.allFinite())
    throw InputError(p.origin + ": a velocity is not finite");
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!(p.radii[i] > 0) || !std::isfinite(p.radii[i]))
      throw InputError(p.origin + ": particle " + std::to_string(i + 1) +
                       " has a radius that is not a positive finite number");
}

}  // namespace

double Packing::mean_radius() const {
  return radii.empty()
             ? 0.0
             : std::accumulate(radii.begin(), radii.end(), 0.0) / static_cast<double>(radii.size());
}

double Packing::volume_fraction() const {
  double v = 0;
  for (double r : radii) v += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  return v / lengths.prod();
}

PackingSource packing_source(const std::string& argument) {
  PackingSource s;
  const auto colon = argument.rfind(':');
  if (colon != std::string::npos && colon > 0 && fs::is_regular_file(argument.substr(0, colon))) {
    s.file = argument.substr(0, colon);
    s.object = argument.substr(colon + 1);
    s.format = PackingFormat::kResultsState;
    if (s.object.empty())
      throw InputError(argument + ": no state after ':' (e.g. FILE.h5:/states/a)");
    if (s.object.front() != '/') {
      if (const std::string why = invalid_object_name_reason(s.object); !why.empty())
        throw InputError(argument + ": state label '" + s.object + "' " + why);
      s.object = paths::state(s.object);
    }
    return s;
  }
  s.file = argument;
  refuse_unless_regular_file(s.file, argument, "packing file",
                             "a LAMMPS data or dump file, or FILE.h5:/states/LABEL");
  std::ifstream in(s.file);
  std::string first;
  std::getline(in, first);
  if (first.rfind("\x89HDF", 0) == 0)
    throw InputError(argument + ": a results file; name the state as " + argument +
                     ":/states/LABEL");
  s.format = first.rfind("ITEM:", 0) == 0 ? PackingFormat::kLammpsDump : PackingFormat::kLammpsData;
  return s;
}

std::string packing_label(const PackingSource& source, const std::string& fallback) {
  if (source.format != PackingFormat::kResultsState) return fallback;
  const auto slash = source.object.rfind('/');
  const std::string last = source.object.substr(slash + 1);
  return last.empty() ? fallback : last;
}

Packing read_packing(const PackingSource& source) {
  switch (source.format) {
    case PackingFormat::kLammpsDump:
      return read_lammps_dump(source.file);
    case PackingFormat::kResultsState:
      return read_results_state(source.file, source.object);
    case PackingFormat::kLammpsData:
      break;
  }
  return read_lammps_data(source.file);
}

Packing read_lammps_data(const fs::path& file) {
  Lines in(file);
  Packing p;
  p.origin = file.string() + " (LAMMPS data file)";
  std::string line;
  in.next(line);  // the title
  // LAMMPS's write_data (since 2022) names the unit style in it: "LAMMPS data file via
  // write_data, version ..., timestep = 0, units = si".
  if (line.rfind("LAMMPS data file via write_data", 0) == 0) {
    constexpr std::string_view kUnits = ", units = ";
    const std::size_t at = line.find(kUnits);
    if (at != std::string::npos) {
      const std::vector<std::string> w = split_words(line.substr(at + kUnits.size()));
      if (!w.empty()) p.units = w[0];
    }
  }
  long long n_atoms = -1;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  bool has_box[3] = {false, false, false};
  const char* axes[3] = {"x", "y", "z"};
  // Header: counts and the box, up to the first section keyword.
  std::string section;
  while (in.next(line)) {
    const std::vector<std::string> w = split_words(strip_comment(line));
    if (w.empty()) continue;
    if (std::isalpha(static_cast<unsigned char>(w[0][0]))) {
      section = line;
      break;
    }
    if (w.size() == 2 && w[1] == "atoms") {
      n_atoms = in.integer(w[0], "atom count");
    } else if (w.size() == 6 && w[3] == "xy") {
      if (in.number(w[0], "xy") != 0 || in.number(w[1], "xz") != 0 || in.number(w[2], "yz") != 0)
        in.fail("a triclinic box (xy xz yz not zero); rendulic's cell is orthorhombic");
    } else if (w.size() == 4) {
      for (int a = 0; a < 3; ++a)
        if (w[2] == std::string(axes[a]) + "lo" && w[3] == std::string(axes[a]) + "hi") {
          lo[a] = in.number(w[0], "box bound");
          hi[a] = in.number(w[1], "box bound");
          check_box(in, lo[a], hi[a], axes[a]);
          has_box[a] = true;
        }
    }
  }
  if (n_atoms < 0) in.fail("no 'N atoms' line in the header");
  if (n_atoms == 0) in.fail("the header says 0 atoms");
  for (int a = 0; a < 3; ++a)
    if (!has_box[a])
      in.fail(std::string("no '") + axes[a] + "lo " + axes[a] + "hi' line in the header");
  const auto n = static_cast<std::size_t>(n_atoms);
  for (int a = 0; a < 3; ++a) p.lengths[a] = hi[a] - lo[a];

  std::vector<long long> ids, vids;
  std::vector<std::array<double, 5>> atoms;  // diameter, density, x, y, z
  std::vector<std::array<double, 3>> vel;
  bool have_atoms = false;
  // Sections: a keyword line, then numeric lines up to the next keyword line.
  while (!section.empty()) {
    const std::vector<std::string> head = split_words(strip_comment(section));
    const auto hash = section.find('#');
    std::string style;
    if (hash != std::string::npos) {
      const std::vector<std::string> sw = split_words(section.substr(hash + 1));
      if (!sw.empty()) style = sw[0];
    }
    const std::string name = head.empty() ? "" : head[0];
    if (name == "Atoms" && !style.empty() && style != "sphere")
      in.fail("the Atoms section is atom_style " + style +
              "; rendulic reads atom_style sphere (id type diameter density x y z)");
    std::string next;
    while (in.next(line)) {
      const std::vector<std::string> w = split_words(strip_comment(line));
      if (w.empty()) continue;
      if (std::isalpha(static_cast<unsigned char>(w[0][0]))) {
        next = line;
        break;
      }
      if (name == "Atoms") {
        if (w.size() != 7 && w.size() != 10)
          in.fail("an Atoms line of " + std::to_string(w.size()) +
                  " columns: not atom_style sphere (id type diameter density x y z [ix iy iz])");
        ids.push_back(in.integer(w[0], "atom id"));
        std::array<double, 5> a{};
        for (int k = 0; k < 5; ++k)
          a[k] = in.number(w[2 + k], k == 0 ? "diameter" : k == 1 ? "density" : "position");
        if (!(a[0] > 0))
          in.fail("a diameter of " + w[2] + ": not a sphere (point particles have 0)");
        // As LAMMPS refuses it ("Invalid density"): the mass would be zero or negative.
        if (!(a[1] > 0)) in.fail("a density of " + w[3] + ": a density is positive");
        atoms.push_back(a);
      } else if (name == "Velocities") {
        if (w.size() < 4) in.fail("a Velocities line of fewer than 4 columns (id vx vy vz)");
        vids.push_back(in.integer(w[0], "atom id"));
        vel.push_back({in.number(w[1], "velocity"), in.number(w[2], "velocity"),
                       in.number(w[3], "velocity")});
      }
    }
    // A section ends at a line that starts with a letter: the next keyword, or a line whose
    // id is not a number (nan, x); a short section says which line ended it.
    const std::string ended_by =
        next.empty() ? std::string()
                     : "; it ends at '" + next.substr(0, 40) + (next.size() > 40 ? "...'" : "'");
    if (name == "Atoms") {
      have_atoms = true;
      if (atoms.size() != n)
        in.fail("the Atoms section has " + std::to_string(atoms.size()) + " lines, the header " +
                std::to_string(n) + " atoms" + ended_by);
    }
    if (name == "Velocities" && vel.size() != n)
      in.fail("the Velocities section has " + std::to_string(vel.size()) + " lines, the header " +
              std::to_string(n) + " atoms" + ended_by);
    section = next;
  }
  if (!have_atoms) in.fail("no Atoms section");
  const std::vector<std::size_t> order = order_by_id(ids, file);
  p.positions.resize(static_cast<Eigen::Index>(n), 3);
  p.radii.resize(n);
  p.densities.resize(n);
  std::map<long long, std::size_t> row_of;
  for (std::size_t k = 0; k < n; ++k) {
    const auto& a = atoms[order[k]];
    row_of[ids[order[k]]] = k;
    p.radii[k] = a[0] / 2;
    p.densities[k] = a[1];
    for (int c = 0; c < 3; ++c)
      p.positions(static_cast<Eigen::Index>(k), c) = wrap(a[2 + c] - lo[c], p.lengths[c]);
  }
  if (!vel.empty()) {
    p.velocities = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), 3);
    for (std::size_t k = 0; k < vel.size(); ++k) {
      const auto it = row_of.find(vids[k]);
      if (it == row_of.end())
        throw InputError(file.string() + ": Velocities name atom id " + std::to_string(vids[k]) +
                         ", which the Atoms section does not have");
      for (int c = 0; c < 3; ++c)
        p.velocities(static_cast<Eigen::Index>(it->second), c) = vel[k][c];
    }
  }
  check_packing(p);
  return p;
}

Packing read_lammps_dump(const fs::path& file) {
  Lines in(file);
  Packing p;
  p.origin = file.string() + " (LAMMPS dump)";
  std::string line;
  bool any = false;
  // Every snapshot is read (so that a damaged one is reported); the last is kept.
  while (in.next(line)) {
    if (line.empty()) continue;
    // `dump_modify units yes` and `time yes` put two items before a snapshot's timestep: the
    // unit style (in the first snapshot only) and the simulated time.
    const std::vector<std::string> item = split_words(line);
    if (item.size() == 2 && item[0] == "ITEM:" && (item[1] == "UNITS" || item[1] == "TIME")) {
      const bool units = item[1] == "UNITS";
      in.need(line, units ? "the unit style" : "the snapshot's time");
      const std::vector<std::string> w = split_words(line);
      if (w.size() != 1)
        in.fail(units ? "the units line needs one word" : "the time line needs one number");
      if (units)
        p.units = w[0];
      else
        in.number(w[0], "time");
      continue;
    }
    if (line.rfind("ITEM: TIMESTEP", 0) != 0) in.fail("expected 'ITEM: TIMESTEP'");
    in.need(line, "the snapshot's timestep");
    const std::vector<std::string> tw = split_words(line);
    if (tw.size() != 1) in.fail("the timestep line needs one integer");
    in.integer(tw[0], "timestep");
    in.need_item(line, "ITEM: NUMBER OF ATOMS");
    in.need(line, "the atom count");
    const std::vector<std::string> nw = split_words(line);
    const long long n_atoms = nw.empty() ? -1 : in.integer(nw[0], "atom count");
    if (n_atoms <= 0) in.fail("the atom count must be positive");
    in.need_item(line, "ITEM: BOX BOUNDS");
    const std::vector<std::string> bw = split_words(line.substr(16));
    if (std::find(bw.begin(), bw.end(), "xy") != bw.end())
      in.fail("a triclinic box (xy xz yz); rendulic's cell is orthorhombic");
    for (const std::string& b : bw)
      if (b != "pp")
        in.fail("boundary '" + b + "': rendulic's cell is periodic on every axis (pp pp pp)");
    double lo[3], hi[3];
    const char* axes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      in.need(line, std::string("the box's ") + axes[a] + " bounds");
      const std::vector<std::string> w = split_words(line);
      if (w.size() < 2) in.fail("a box line needs lo and hi");
      lo[a] = in.number(w[0], "box bound");
      hi[a] = in.number(w[1], "box bound");
      check_box(in, lo[a], hi[a], axes[a]);
      p.lengths[a] = hi[a] - lo[a];
    }
    in.need_item(line, "ITEM: ATOMS");
    const std::vector<std::string> cols = split_words(line.substr(11));
    auto column = [&](std::initializer_list<const char*> names) -> int {
      for (const char* nm : names)
        for (std::size_t c = 0; c < cols.size(); ++c)
          if (cols[c] == nm) return static_cast<int>(c);
      return -1;
    };
    const int c_id = column({"id"});
    const int c_r = column({"radius"}), c_d = column({"diameter"});
    if (c_r < 0 && c_d < 0) in.fail("no radius or diameter column among the ATOMS columns");
    int c_x[3];
    bool scaled = false;
    {
      const char* sets[4][3] = {
          {"x", "y", "z"}, {"xu", "yu", "zu"}, {"xs", "ys", "zs"}, {"xsu", "ysu", "zsu"}};
      int found = -1;
      for (int s = 0; s < 4 && found < 0; ++s) {
        for (int a = 0; a < 3; ++a) c_x[a] = column({sets[s][a]});
        if (c_x[0] >= 0 && c_x[1] >= 0 && c_x[2] >= 0) found = s;
      }
      if (found < 0) in.fail("no position columns (x y z, xu yu zu, xs ys zs or xsu ysu zsu)");
      scaled = found >= 2;
    }
    // Each velocity by its own name: `dump custom` writes the columns in any order.
    const int c_v[3] = {column({"vx"}), column({"vy"}), column({"vz"})};
    const bool has_v = c_v[0] >= 0 && c_v[1] >= 0 && c_v[2] >= 0;
    const auto n = static_cast<std::size_t>(n_atoms);
    // Grown line by line: the header's count is not trusted with memory (a damaged count of
    // 10^12 asked for 40 TB before the first line was read).
    std::vector<long long> ids;
    std::vector<Eigen::Vector3d> x, v;
    std::vector<double> r;
    for (std::size_t k = 0; k < n; ++k) {
      if (!in.next(line))
        in.fail("the snapshot ends after " + std::to_string(k) + " of " + std::to_string(n) +
                " atoms");
      const std::vector<std::string> w = split_words(line);
      if (w.size() != cols.size())
        in.fail("a line of " + std::to_string(w.size()) + " columns; ITEM: ATOMS names " +
                std::to_string(cols.size()));
      ids.push_back(c_id >= 0 ? in.integer(w[static_cast<std::size_t>(c_id)], "atom id")
                              : static_cast<long long>(k));
      r.push_back(c_r >= 0 ? in.number(w[static_cast<std::size_t>(c_r)], "radius")
                           : in.number(w[static_cast<std::size_t>(c_d)], "diameter") / 2);
      Eigen::Vector3d xk, vk;
      for (int a = 0; a < 3; ++a) {
        double q = in.number(w[static_cast<std::size_t>(c_x[a])], "position");
        q = scaled ? q * p.lengths[a] : q - lo[a];
        xk[a] = wrap(q, p.lengths[a]);
        if (has_v) vk[a] = in.number(w[static_cast<std::size_t>(c_v[a])], "velocity");
      }
      x.push_back(xk);
      if (has_v) v.push_back(vk);
    }
    const std::vector<std::size_t> order = order_by_id(ids, file);
    p.positions.resize(static_cast<Eigen::Index>(n), 3);
    p.radii.resize(n);
    p.velocities.resize(has_v ? static_cast<Eigen::Index>(n) : 0, 3);
    for (std::size_t k = 0; k < n; ++k) {
      p.positions.row(static_cast<Eigen::Index>(k)) = x[order[k]];
      p.radii[k] = r[order[k]];
      if (has_v) p.velocities.row(static_cast<Eigen::Index>(k)) = v[order[k]];
    }
    any = true;
  }
  if (!any) throw InputError(file.string() + ": no snapshot in the dump");
  check_packing(p);
  return p;
}

namespace {

// "; its states are a, b": the labels that hold a configuration in the states group the asked
// `group` would be in (a pressure branch's for /pressure/nu0.7/states/x, else /states), so that
// a mistyped label or a group that is not a state can be mended without another command.
std::string its_states(const ResultsReader& r, const std::string& group) {
  constexpr std::size_t kShown = 12;
  std::string root;
  for (const std::string& candidate : state_roots(r))
    if (!candidate.empty() && group.rfind(paths::states(candidate) + "/", 0) == 0) root = candidate;
  const std::string where = root.empty() ? "its states are " : "the states of " + root + " are ";
  if (!r.is_group(paths::states(root))) return "; it holds no " + paths::states(root) + " group";
  std::vector<std::string> labels;
  for (const std::string& c : r.children(paths::states(root)))
    if (r.exists(paths::state(c, root) + datasets::kPositions)) labels.push_back(c);
  if (labels.empty()) return "; no state in " + paths::states(root) + " holds a configuration";
  return "; " + where + comma_list(labels, "", kShown, " (rendulic inspect)");
}

}  // namespace

Packing read_results_state(const fs::path& file, const std::string& group) {
  const ResultsReader r(file);
  if (!r.is_group(group))
    throw InputError(file.string() + ": no state " + group + its_states(r, group));
  Packing p;
  p.origin = file.string() + ":" + group;
  const std::string pos = group + datasets::kPositions;
  if (!r.exists(pos))
    throw InputError(p.origin + ": not a state (it holds no positions and radii)" +
                     its_states(r, group));
  p.positions = r.read_matrix(pos);
  p.radii = r.read_vector(group + datasets::kRadii);
  const std::vector<double> L = r.read_vector(group + datasets::kCellLengths);
  if (L.size() != 3) throw InputError(p.origin + ": cell_lengths must hold 3 numbers");
  p.lengths = Eigen::Vector3d(L[0], L[1], L[2]);
  if (p.positions.cols() != 3 || static_cast<std::size_t>(p.positions.rows()) != p.radii.size())
    throw InputError(p.origin + ": positions must be [N,3] with N = number of radii");
  const std::string vel = group + paths::kCheckpoint + datasets::kVelocities;
  if (r.exists(vel)) {
    p.velocities = r.read_matrix(vel);
    if (p.velocities.rows() != p.positions.rows() || p.velocities.cols() != 3)
      throw InputError(p.origin + ": checkpoint velocities must be [N,3]");
  }
  check_packing(p);
  return p;
}

void write_lammps_data(const fs::path& file, const Packing& p, double density,
                       const std::string& title) {
  AtomicTextFile f(file, "the LAMMPS data file");
  std::ostream& out = f.stream();
  const Eigen::Vector3d& L = p.lengths;
  out << std::setprecision(17) << title << "\n\n"
      << p.size() << " atoms\n1 atom types\n\n"
      << "0 " << L[0] << " xlo xhi\n0 " << L[1] << " ylo yhi\n0 " << L[2] << " zlo zhi\n\n"
      << "Atoms # sphere\n\n";
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    out << i + 1 << " 1 " << 2 * p.radii[i] << " " << density;
    for (int a = 0; a < 3; ++a) out << " " << wrap(p.positions(r, a), L[a]);
    out << "\n";
  }
  out << "\nVelocities\n\n";
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    out << i + 1;
    for (int a = 0; a < 3; ++a) out << " " << (p.velocities.rows() > 0 ? p.velocities(r, a) : 0.0);
    out << " 0 0 0\n";
  }
  f.commit();
}

}  // namespace rendulic
