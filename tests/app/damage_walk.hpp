// The damaged-file walk (docs/usage.md "Results are atomic"; docs/results.md): every
// subcommand that reads a results file run on damaged copies of a real one (every group,
// dataset and attribute missing, wrongly typed or empty in turn), each refusal one line that
// names the file, exit 2, nothing left half-written. faults_system_test.cpp walks every damage
// with one command (the damage's own pick, below), the damage every command needs with all of
// them and the figure script over three damages; faults_validate_test.cpp walks every damage
// with every command and the figure script over eight (2400 runs of the binary: minutes on 2
// cores).
#pragma once

#include <H5Cpp.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_runner.hpp"

namespace rendulic::testing {
namespace fs = std::filesystem;

// Temporary files in a folder: anything a writer leaves while it works.
inline std::vector<std::string> temporaries(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.find(".tmp") != std::string::npos) out.push_back(n);
  }
  return out;
}

inline int lines(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

struct Damage {
  std::string what;  // "missing /path/time", "wrongly typed /material @k_star", ...
  std::string object;
  std::function<void(H5::H5File&)> apply;
};

struct Attribute {
  std::string name;
  bool text, array;
};

struct Object {
  std::string path;
  bool group;
  std::vector<Attribute> attributes;
};

// The path with every state label and envelope name replaced by "*": the states (and their
// envelopes) of a file repeat one structure, read by the same code.
inline std::string structure_of(const std::string& path) {
  std::string out;
  std::istringstream in(path);
  std::string previous;
  for (std::string part; std::getline(in, part, '/');) {
    if (part.empty()) continue;
    // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "/" + string
    // here once inlined into a larger test.
    out += '/';
    out += previous == "states" || previous == "envelopes" ? std::string("*") : part;
    previous = part;
  }
  return out.empty() ? "/" : out;
}

struct Visit {
  std::vector<Object> objects;
  std::set<std::string> structures;
};

inline herr_t visit(hid_t, const char* name, const H5O_info_t* info, void* data) {
  auto* v = static_cast<Visit*>(data);
  const std::string path = std::string(name) == "." ? "/" : "/" + std::string(name);
  // The first state and the first envelope stand for all.
  if (v->structures.insert(structure_of(path)).second)
    v->objects.push_back({path, info->type == H5O_TYPE_GROUP, {}});
  return 0;
}

inline std::vector<Object> objects_of(const fs::path& file) {
  Visit v;
  H5::H5File h(file.string(), H5F_ACC_RDONLY);
  H5Ovisit2(h.getId(), H5_INDEX_NAME, H5_ITER_INC, visit, &v, H5O_INFO_BASIC);
  std::vector<Object>& objects = v.objects;
  for (auto& o : objects) {
    const hid_t id = H5Oopen(h.getId(), o.path.c_str(), H5P_DEFAULT);
    H5O_info_t info;
    H5Oget_info2(id, &info, H5O_INFO_NUM_ATTRS);
    for (hsize_t i = 0; i < info.num_attrs; ++i) {
      const hid_t a =
          H5Aopen_by_idx(id, ".", H5_INDEX_NAME, H5_ITER_NATIVE, i, H5P_DEFAULT, H5P_DEFAULT);
      char name[256] = {0};
      H5Aget_name(a, sizeof name, name);
      const hid_t t = H5Aget_type(a);
      const hid_t sp = H5Aget_space(a);
      o.attributes.push_back(
          {name, H5Tget_class(t) == H5T_STRING, H5Sget_simple_extent_ndims(sp) > 0});
      H5Sclose(sp);
      H5Tclose(t);
      H5Aclose(a);
    }
    H5Oclose(id);
  }
  return objects;
}

inline void delete_children(H5::H5File& h, const std::string& group) {
  H5::Group g = h.openGroup(group);
  std::vector<std::string> names;
  for (hsize_t i = 0; i < g.getNumObjs(); ++i) names.push_back(g.getObjnameByIdx(i));
  for (const auto& n : names) g.unlink(n);
}

// Every group and dataset missing, wrongly typed (a group as numbers, numbers as text) and
// empty (no members, no rows); every attribute missing and wrongly typed (text for a number, a
// number for text), and every numeric array attribute empty. Of the states and envelopes, the
// first stands for all (structure_of).
inline std::vector<Damage> damages_of(const fs::path& file) {
  std::vector<Damage> out;
  static const hsize_t two = 2;
  for (const Object& o : objects_of(file)) {
    const std::string p = o.path;
    if (p != "/") {
      out.push_back({"missing " + p, p, [p](H5::H5File& h) { h.unlink(p); }});
      out.push_back({"wrongly typed " + p, p, [p, g = o.group](H5::H5File& h) {
                       h.unlink(p);
                       if (g)
                         h.createDataSet(p, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(1, &two));
                       else
                         h.createDataSet(p, H5::StrType(H5::PredType::C_S1, 4),
                                         H5::DataSpace(1, &two));
                     }});
      const bool childless =
          o.group && H5::H5File(file.string(), H5F_ACC_RDONLY).openGroup(p).getNumObjs() == 0;
      if (!childless)  // else nothing to empty
        out.push_back({"empty " + p, p, [p, g = o.group](H5::H5File& h) {
                         if (g) return delete_children(h, p);
                         H5::DataSet ds = h.openDataSet(p);
                         std::vector<hsize_t> dims(ds.getSpace().getSimpleExtentNdims());
                         ds.getSpace().getSimpleExtentDims(dims.data());
                         ds.close();
                         h.unlink(p);
                         if (dims.empty()) dims.push_back(0);
                         dims[0] = 0;
                         h.createDataSet(p, H5::PredType::NATIVE_DOUBLE,
                                         H5::DataSpace(static_cast<int>(dims.size()), dims.data()));
                       }});
    }
    for (const auto& [name, text, array] : o.attributes) {
      const std::string where = p + " @" + name;
      auto with_object = [p, g = o.group](H5::H5File& h,
                                          const std::function<void(H5::H5Object&)>& fn) {
        if (g) {
          H5::Group obj = h.openGroup(p);
          fn(obj);
        } else {
          H5::DataSet obj = h.openDataSet(p);
          fn(obj);
        }
      };
      const std::string n = name;
      out.push_back({"missing " + where, p, [with_object, n](H5::H5File& h) {
                       with_object(h, [&](H5::H5Object& obj) { obj.removeAttr(n); });
                     }});
      out.push_back({"wrongly typed " + where, p, [with_object, n, text = text](H5::H5File& h) {
                       with_object(h, [&](H5::H5Object& obj) {
                         obj.removeAttr(n);
                         if (text) {
                           const double one = 1.0;
                           obj.createAttribute(n, H5::PredType::NATIVE_DOUBLE,
                                               H5::DataSpace(H5S_SCALAR))
                               .write(H5::PredType::NATIVE_DOUBLE, &one);
                         } else {
                           const H5::StrType t(H5::PredType::C_S1, 1);
                           obj.createAttribute(n, t, H5::DataSpace(H5S_SCALAR)).write(t, "x");
                         }
                       });
                     }});
      if (!text && array)
        out.push_back({"empty " + where, p, [with_object, n](H5::H5File& h) {
                         with_object(h, [&](H5::H5Object& obj) {
                           obj.removeAttr(n);
                           const hsize_t zero = 0;
                           obj.createAttribute(n, H5::PredType::NATIVE_DOUBLE,
                                               H5::DataSpace(1, &zero));
                         });
                       }});
    }
  }
  return out;
}

// Which commands walk a damage: all of them for `every_command`, and for the damage every
// command needs (the schema, the states as a group); else one, picked by a hash of the
// damage's name (FNV-1a) so that the kinds of damage of one object (missing, wrongly typed,
// empty: neighbours in the list) fall to different commands.
enum class Coverage { one_command_each, every_command };

// The figure script (Python and matplotlib, 8 s and 14 s of CPU a run on a tiny run's file) is
// walked over a sample: damage to what each figure draws from, of the kinds its own handling
// does not cover; with one command each, over three of them (a group, a dataset, an
// attribute).
inline std::set<std::string> plot_sample(Coverage coverage) {
  if (coverage == Coverage::one_command_each)
    return {"wrongly typed /states", "empty /path/fabric",
            "wrongly typed /states/a/envelopes/dynamic_0.002/fit_stress @semi_axes"};
  return {
      "wrongly typed /states",
      "wrongly typed /isotropic/pressure_star",
      "wrongly typed /path/stress_star",
      "empty /path/fabric",
      "wrongly typed /states/a/envelopes/dynamic_0.002/stress_star",
      "empty /states/a/envelopes/dynamic_0.002/theta_deg",
      "wrongly typed /states/a/envelopes/dynamic_0.002/fit_stress @semi_axes",
      "wrongly typed /states/a/envelopes/dynamic_0.002 @amplitude",
  };
}

inline bool every_command_needs(const std::string& what) {
  return what == "missing / @schema" || what == "wrongly typed / @schema" ||
         what == "wrongly typed /states";
}

inline std::size_t pick_of(const std::string& what, std::size_t n) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : what) h = (h ^ c) * 1099511628211ull;
  return static_cast<std::size_t>(h % n);
}

// Walks the damaged copies of `base` in the test folder `name` (fresh_dir: made afresh,
// removed at the end) and writes every outcome to `outcomes_file`.
inline void walk_damaged_copies(const fs::path& base, const std::string& name,
                                const fs::path& outcomes_file, Coverage coverage) {
  ASSERT_TRUE(fs::exists(base));
  const std::vector<Damage> damages = damages_of(base);
  const fs::path root = fresh_dir(name);
  struct Run {
    std::size_t damage;
    std::string command;
  };
  std::vector<Run> runs;
  const std::set<std::string> plot_walks = plot_sample(coverage);
  int plots = 0;
  for (std::size_t i = 0; i < damages.size(); ++i) {
    const fs::path f = root / std::to_string(i) / "results.h5";
    fs::create_directories(f.parent_path());
    fs::copy_file(base, f);
    {
      H5::H5File h(f.string(), H5F_ACC_RDWR);
      damages[i].apply(h);
    }
    static const char* const commands[] = {
        "inspect", "report --no-figures",
        "calibrate --model isotropic_elastic --max-iterations 5 --results"};
    const bool all = coverage == Coverage::every_command || every_command_needs(damages[i].what);
    const std::size_t pick = pick_of(damages[i].what, std::size(commands));
    auto add = [&](std::size_t c) {
      if (all || c == pick) runs.push_back({i, commands[c]});
    };
    add(0), add(1);
    if (plot_walks.count(damages[i].what)) runs.push_back({i, "plot"}), ++plots;
    add(2);  // calibrate last: it changes the file the others read
  }
  EXPECT_EQ(plots, static_cast<int>(plot_walks.size()));
  for (const auto& w : plot_walks)
    EXPECT_TRUE(std::any_of(damages.begin(), damages.end(), [&](auto& d) { return d.what == w; }))
        << "not among the walk's damage: " << w;
  // Two workers, each on whole copies: a copy's runs go in order (calibrate, last, changes
  // the file the others read).
  std::vector<CliResult> results(runs.size());
  std::vector<std::vector<std::size_t>> by_copy(damages.size());
  for (std::size_t k = 0; k < runs.size(); ++k) by_copy[runs[k].damage].push_back(k);
  std::atomic<std::size_t> next_copy{0};
  auto worker = [&] {
    for (std::size_t c; (c = next_copy++) < by_copy.size();)
      for (std::size_t k : by_copy[c]) {
        const fs::path f = root / std::to_string(c) / "results.h5";
        results[k] = rendulic::testing::run_rendulic(runs[k].command + " " + f.string(), false);
      }
  };
  std::thread t1(worker), t2(worker);
  t1.join();
  t2.join();

  // Every outcome, for a reader who wants to see what each command made of each damage.
  std::ofstream outcomes(outcomes_file);
  std::map<std::string, std::pair<int, int>> tally;  // command -> refused, accepted
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Damage& d = damages[runs[k].damage];
    const CliResult& r = results[k];
    const std::string cmd = runs[k].command.substr(0, runs[k].command.find(' '));
    const std::string where = cmd + " on " + d.what + ": ";
    const fs::path dir = root / std::to_string(runs[k].damage);
    outcomes << where << "exit " << r.code << (r.code ? " " + r.err : std::string("\n"));
    EXPECT_TRUE(r.code == 0 || r.code == 2) << where << "exit " << r.code << "\n" << r.err;
    if (r.code == 2) {
      ++tally[cmd].first;
      EXPECT_EQ(lines(r.err), 1) << where << r.err;
      EXPECT_EQ(r.err.rfind("rendulic: ", 0), 0u) << where << r.err;
      EXPECT_NE(r.err.find("results.h5"), std::string::npos)
          << where << "names the file: " << r.err;
    } else {
      ++tally[cmd].second;
    }
    EXPECT_TRUE(temporaries(dir).empty()) << where << temporaries(dir).front();
  }
  std::ostringstream summary;
  for (const auto& [cmd, n] : tally)
    summary << cmd << ": " << n.first << " refused, " << n.second << " accepted; ";
  std::cout << damages.size() << " damaged copies, " << runs.size() << " runs: " << summary.str()
            << "\n";
  // A walk that refuses nothing tests nothing: every command must meet damage it needs.
  for (const char* cmd : {"inspect", "report", "plot", "calibrate"})
    EXPECT_GT(tally[cmd].first, 0) << cmd << " refused no damaged copy";
  // Damage every command needs: the schema, and the states as a group.
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const std::string& what = damages[runs[k].damage].what;
    // inspect lists what a file holds: /states of the wrong type is one more thing to list.
    const bool needed = every_command_needs(what) &&
                        !(what == "wrongly typed /states" && runs[k].command == "inspect");
    if (needed) {
      EXPECT_EQ(results[k].code, 2) << runs[k].command << " on " << what;
    }
  }
  fs::remove_all(root);
}

}  // namespace rendulic::testing
