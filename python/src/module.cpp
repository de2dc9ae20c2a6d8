// The extension module `rendulic._rendulic` (docs/python.md): results files read into numpy
// without HDF5 paths, envelope fits, model envelopes and material-point paths, probing a packing
// and running a scenario, each through the very functions the CLI calls (app/commands.hpp,
// probes/, models/, core/results.hpp), so that its numbers are the CLI's. The package's
// __init__.py wraps these dictionaries into small dataclasses.
//
// Long work releases the GIL. Its progress comes through app/progress.hpp's observer: on the
// thread that called in, the GIL is taken again, Python's pending signals are run
// (PyErr_CheckSignals: Ctrl-C becomes KeyboardInterrupt) and the user's callback is called;
// either raising asks the work to stop (request_stop), the C++ side unwinds as it does for any
// error (temporary files removed, completed stages kept), and the Python exception is raised.
// rendulic::InputError arrives as rendulic.InputError (a ValueError) with the CLI's one-line
// message.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <signal.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "commands.hpp"
#include "progress.hpp"
#include "rendulic/calibration/report.hpp"
#include "rendulic/calibration/solver.hpp"
#include "rendulic/core/cleanup.hpp"
#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/scenario.hpp"
#include "rendulic/models/paths.hpp"
#include "rendulic/probes/envelope.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#include "rendulic/probes/fit_io.hpp"

namespace py = pybind11;
using namespace py::literals;

namespace rendulic::python {
namespace {

// ---- numpy out ----------------------------------------------------------------------------

py::array_t<double> array_of(const std::vector<double>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}
py::array_t<double> pairs_of(const std::vector<Eigen::Vector2d>& v) {
  py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{2}});
  auto m = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int j = 0; j < 2; ++j) m(static_cast<py::ssize_t>(i), j) = v[i](j);
  return a;
}
py::array_t<double> tensors_of(const std::vector<Eigen::Matrix3d>& v) {
  py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}, py::ssize_t{3}});
  auto m = a.mutable_unchecked<3>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m(static_cast<py::ssize_t>(i), r, c) = v[i](r, c);
  return a;
}
py::array_t<double> matrix_of(const Eigen::MatrixXd& x) {
  py::array_t<double> a({static_cast<py::ssize_t>(x.rows()), static_cast<py::ssize_t>(x.cols())});
  auto m = a.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    for (Eigen::Index c = 0; c < x.cols(); ++c) m(r, c) = x(r, c);
  return a;
}

// ---- results files ------------------------------------------------------------------------

// Every attribute of an object: numbers as a float (one) or an array, texts as str (a list of
// texts as a list).
py::dict attrs_of(const ResultsReader& in, const std::string& object) {
  py::dict d;
  for (const std::string& name : in.attr_names(object)) {
    if (in.attr_is_text(object, name)) {
      try {
        d[py::str(name)] = in.attr_string(object, name);
      } catch (const InputError&) {  // a list of texts
        d[py::str(name)] = in.attr_strings(object, name);
      }
    } else {
      const std::vector<double> v = in.attr_doubles(object, name);
      if (v.size() == 1)
        d[py::str(name)] = v[0];
      else
        d[py::str(name)] = array_of(v);
    }
  }
  return d;
}

// A dataset as an array of its own shape.
py::array_t<double> dataset(const ResultsReader& in, const std::string& path) {
  const std::vector<std::uint64_t> shape = in.shape(path);
  if (shape.size() == 3 && shape[1] == 3 && shape[2] == 3) return tensors_of(in.read_tensors(path));
  if (shape.size() == 2 && shape[0] == 3 && shape[1] == 3) return matrix_of(in.read_tensor(path));
  if (shape.size() == 2) return matrix_of(in.read_matrix(path));
  if (shape.size() <= 1) return array_of(in.read_vector(path));
  throw InputError(in.path().string() + ": " + path + ": a dataset of " +
                   std::to_string(shape.size()) + " dimensions is not read here");
}

// Every dataset of a group, by name (child groups left out).
py::dict datasets_of(const ResultsReader& in, const std::string& group) {
  py::dict d;
  for (const std::string& name : in.children(group)) {
    const std::string path = group + "/" + name;
    if (!in.is_group(path)) d[py::str(name)] = dataset(in, path);
  }
  return d;
}

py::dict fit_dict(const EnvelopeFit& f) {
  py::dict d;
  d["shape"] = to_string(f.shape);
  d["center"] = py::make_tuple(f.center.x(), f.center.y());
  d["semi_axes"] = py::make_tuple(f.a, f.b);
  d["inclination_deg"] =
      f.inclination_deg ? py::object(py::float_(*f.inclination_deg)) : py::none();
  d["rms"] = f.rms;
  py::dict se;
  if (f.has_stderr) {
    se["center"] = py::make_tuple(f.center_stderr.x(), f.center_stderr.y());
    se["semi_axes"] = py::make_tuple(f.a_stderr, f.b_stderr);
    if (f.inclination_stderr_deg) se["inclination_deg"] = *f.inclination_stderr_deg;
  }
  d["stderr"] = se;
  d["covariance"] = matrix_of(f.covariance);
  d["residuals"] = array_of(f.residuals);
  d["n_points"] = f.n_points;
  d["loss"] = to_string(f.loss);
  d["loss_scale"] = f.loss_scale;
  d["converged"] = f.converged;
  d["used_theta"] = f.used_theta;
  d["selection"] = f.selection_note;
  d["line_p_value"] = f.line_p_value ? py::object(py::float_(*f.line_p_value)) : py::none();
  return d;
}

py::dict envelope_dict(const ResultsReader& in, const std::string& group) {
  const EnvelopeRecord e = read_envelope(in, group);
  py::dict d;
  d["method"] = e.method;
  d["amplitude"] = e.amplitude;
  d["k_star"] = e.k_star;
  d["plane"] = e.plane.name;
  d["theta_deg"] = array_of(e.theta_deg);
  d["strain"] = pairs_of(e.strain);
  d["stress_star"] = pairs_of(e.stress_star);
  d["fabric"] = pairs_of(e.fabric);
  d["d_stress"] = tensors_of(e.d_stress);
  d["d_fabric"] = tensors_of(e.d_fabric);
  py::dict split;
  if (!e.d_fabric_volume.empty()) {
    split["volume"] = tensors_of(e.d_fabric_volume);
    split["rotation"] = tensors_of(e.d_fabric_rotation);
    split["contacts"] = tensors_of(e.d_fabric_contacts);
  }
  d["d_fabric_split"] = split;
  py::dict diag;
  for (const auto& [k, v] : e.diagnostics) diag[py::str(k)] = array_of(v);
  d["diagnostics"] = diag;
  d["attributes"] = attrs_of(in, group);
  for (const char* m : {datasets::kStiffness, datasets::kFabricStiffness})
    if (in.exists(group + m)) d[py::str(m + 1)] = matrix_of(in.read_matrix(group + m));
  for (const auto& [key, sub] :
       {std::pair{"fit_stress", paths::kFitStress}, std::pair{"fit_fabric", paths::kFitFabric}}) {
    const std::string g = group + sub;
    if (in.is_group(g) && in.has_attr(g, "semi_axes"))
      d[key] = fit_dict(read_envelope_fit(in, g));
    else if (in.is_group(g) && in.has_attr(g, "error"))
      d[key] = py::dict("shape"_a = "none", "error"_a = in.attr_string(g, "error"));
    else
      d[key] = py::none();
  }
  return d;
}

class Reader {
 public:
  explicit Reader(const std::string& path) : in_(path) {}

  std::string path() const { return in_.path().string(); }
  std::vector<std::string> children(const std::string& group) const { return in_.children(group); }
  py::dict attrs(const std::string& object) const { return attrs_of(in_, object); }
  py::array_t<double> read(const std::string& path) const { return dataset(in_, path); }

  // A root that is not the run's own ("") nor a pressure branch gave no states and no
  // envelopes, as if the branch were empty: a mistyped root ("nu0.7") looked like no data.
  std::vector<std::string> states(const std::string& root) const {
    const std::vector<std::string> roots = state_roots(in_);
    if (std::find(roots.begin(), roots.end(), root) == roots.end())
      throw InputError(path() + ": no pressure branch '" + root +
                       "' (branches: " + joined(pressure_branches(in_)) + ")");
    return in_.children(paths::states(root));
  }
  // The group of a state, which must be there: envelope_names of a mistyped label was [].
  // (The lists are read only for the refusal: envelopes() calls this for every envelope.)
  std::string state_group(const std::string& label, const std::string& root) const {
    const std::string g = paths::state(label, root);
    // A label is one name: '' (the states' own group) and 'a/envelopes' were groups "with no
    // stress".
    if (!label.empty() && label.find('/') == std::string::npos && in_.is_group(g)) return g;
    const std::vector<std::string> labels = states(root);  // a root not there is named first
    throw InputError(path() + ": no state '" + label + "'" +
                     (root.empty() ? "" : " under " + root) + " (states: " + joined(labels) + ")");
  }
  py::dict state(const std::string& label, const std::string& root) const {
    const std::string g = state_group(label, root);
    py::dict d = datasets_of(in_, g);
    // A State has a 3x3 stress and fabric: a missing one was a KeyError, one of shape (0, 3) a
    // State that no tensor formula can take.
    for (const char* tensor : {datasets::kStress, datasets::kFabric}) {
      if (!in_.exists(g + tensor))
        throw InputError(path() + ": state '" + label + "' has no " + (tensor + 1));
      d[py::str(tensor + 1)] = matrix_of(in_.read_tensor(g + tensor));
    }
    d["label"] = label;
    d["attributes"] = attrs_of(in_, g);
    return d;
  }
  std::vector<std::string> envelopes(const std::string& label, const std::string& root) const {
    return in_.children(paths::envelopes(state_group(label, root)));
  }
  py::dict envelope(const std::string& label, const std::string& name,
                    const std::string& root) const {
    const std::string g = paths::envelope(state_group(label, root), name);
    if (!in_.is_group(g))
      throw InputError(path() + ": state '" + label + "' has no envelope '" + name +
                       "' (envelopes: " + joined(envelopes(label, root)) + ")");
    py::dict d = envelope_dict(in_, g);
    d["state"] = label;
    d["name"] = name;
    return d;
  }
  // A series (/isotropic, /path, a branch's path) as a dictionary of arrays and its attributes.
  py::dict series(const std::string& group) const {
    if (!in_.is_group(group)) throw InputError(path() + ": no series " + group);
    py::dict d = datasets_of(in_, group);
    d["attributes"] = attrs_of(in_, group);
    return d;
  }
  std::vector<std::string> branches() const { return pressure_branches(in_); }
  py::dict calibration() const {
    py::dict d;
    if (!in_.is_group(paths::kCalibration)) return d;
    d["attributes"] = attrs_of(in_, paths::kCalibration);
    py::dict models;
    for (const std::string& model : in_.children(paths::kCalibration)) {
      const std::string g = paths::calibration(model);
      if (!in_.is_group(g)) continue;
      py::dict m;
      py::dict a = attrs_of(in_, g);
      m["attributes"] = a;
      const calibration::StoredParameters stored = calibration::read_parameters(in_, g);
      py::dict p, se;
      for (std::size_t i = 0; i < stored.names.size(); ++i) {
        p[py::str(stored.names[i])] = stored.values[i];
        if (!stored.stderr_.empty()) se[py::str(stored.names[i])] = stored.stderr_[i];
      }
      m["params"] = p;
      m["stderr"] = se;
      if (in_.exists(g + datasets::kCorrelation))
        m["correlation"] = matrix_of(in_.read_matrix(g + datasets::kCorrelation));
      py::dict states;
      const std::string sg = paths::states(g);
      for (const std::string& label : in_.children(sg)) {
        py::dict s;
        s["attributes"] = attrs_of(in_, paths::state(label, g));
        py::dict envs;
        const std::string eg = paths::envelopes(paths::state(label, g));
        for (const std::string& name : in_.children(eg))
          envs[py::str(name)] = envelope_dict(in_, paths::envelope(paths::state(label, g), name));
        s["envelopes"] = envs;
        states[py::str(label)] = s;
      }
      m["states"] = states;
      if (in_.is_group(g + paths::kPath)) m["path"] = series(g + paths::kPath);
      models[py::str(model)] = m;
    }
    d["models"] = models;
    return d;
  }

 private:
  static std::string joined(const std::vector<std::string>& v) { return comma_list(v, "none"); }
  ResultsReader in_;
};

// ---- long work: GIL, progress, Ctrl-C -----------------------------------------------------

// The Python exception that asked the work to stop (KeyboardInterrupt, or the callback's own).
struct PendingError {
  py::object type, value, trace;
  bool set() const { return static_cast<bool>(type); }
  void fetch() {
    PyObject *t = nullptr, *v = nullptr, *tb = nullptr;
    PyErr_Fetch(&t, &v, &tb);
    PyErr_NormalizeException(&t, &v, &tb);
    type = py::reinterpret_steal<py::object>(t);
    value = py::reinterpret_steal<py::object>(v);
    trace = py::reinterpret_steal<py::object>(tb);
  }
  [[noreturn]] void raise() {
    PyErr_Restore(type.release().ptr(), value.release().ptr(), trace.release().ptr());
    throw py::error_already_set();
  }
};

// Under the GIL: Ctrl-C (PyErr_CheckSignals, as KeyboardInterrupt) and the user's progress
// callback (or None). Either's exception is kept in `pending`; false says the work should stop.
bool tell_python(PendingError& pending, const py::object& callback, const std::string& stage,
                 const std::string& task, double fraction) {
  py::gil_scoped_acquire gil;
  if (pending.set()) return false;
  if (PyErr_CheckSignals() != 0) {
    pending.fetch();
    return false;
  }
  if (callback.is_none()) return true;
  try {
    callback(stage, task, fraction);
  } catch (py::error_already_set& e) {
    e.restore();
    pending.fetch();
    return false;
  }
  return true;
}

// The progress observer, the stop flag (app/progress.hpp) and the log level are the process's:
// two calls in two threads at once swapped each other's callbacks, and one's stop stopped the
// other. So long calls take turns, and one started from a progress callback (which would reset
// the outer call's observer when it ends) is refused.
std::mutex& long_work_turn() {
  static std::mutex m;
  return m;
}
thread_local bool in_long_work = false;

// Runs `work` without the GIL, with progress reported to `callback(stage, task, fraction)` (or
// None) and Ctrl-C honoured. `quiet` silences the info lines on stderr for this call only.
template <class Work>
auto long_work(const py::object& callback, bool quiet, Work&& work) {
  if (in_long_work)
    throw std::runtime_error(
        "rendulic.run and rendulic.probe cannot be called from a progress callback: the call "
        "that reports is still running");
  std::unique_lock<std::mutex> turn(long_work_turn(), std::try_to_lock);
  if (!turn.owns_lock()) {
    log::info(
        "waiting for another rendulic.run or rendulic.probe of this process (another "
        "thread) to finish");
    py::gil_scoped_release release;  // the running call's callback needs the GIL
    turn.lock();
  }
  in_long_work = true;
  struct Leave {
    ~Leave() { in_long_work = false; }
  } leave;
  PendingError pending;
  const std::thread::id owner = std::this_thread::get_id();
  app::clear_stop();
  app::set_progress_observer(
      [&](const std::string& stage, const std::string& task, double fraction) {
        // Python's signals are run on its main thread only, and the callback is called from one
        // thread: the one that called in (the master of every OpenMP team it opens).
        if (std::this_thread::get_id() != owner) return;
        if (!tell_python(pending, callback, stage, task, fraction)) app::request_stop();
      });
  const log::Level level = log::level();
  if (quiet) log::set_level(log::Level::kWarning);
  const auto done = [&] {
    app::set_progress_observer({});
    app::clear_stop();
    log::set_level(level);
  };
  std::string failure;
  std::exception_ptr error;
  using Result = decltype(work());
  std::optional<Result> result;
  {
    py::gil_scoped_release release;
    try {
      result.emplace(work());
    } catch (...) {
      error = std::current_exception();
      failure = describe_current_exception();
    }
  }
  done();
  if (pending.set()) {
    // The stop the user asked for; what the C++ side said on the way out (the stages kept in
    // results.h5.partial) travels as a note.
    if (error && failure.find("stopped on request") == std::string::npos &&
        py::hasattr(pending.value, "add_note"))
      pending.value.attr("add_note")(failure);
    pending.raise();
  }
  if (error) std::rethrow_exception(error);
  return std::move(*result);
}

// ---- inputs -------------------------------------------------------------------------------

// A dictionary of numbers (law parameters) or of a state's stress, fabric (3x3) and
// volume_fraction as TOML text, checked afterwards by the same readers as a file.
std::string toml_of(const py::dict& d, const char* what) {
  std::ostringstream out;
  for (const auto& [k, v] : d) {
    const std::string key = py::str(k);
    // Quoted as TOML quotes it: {'K" = 5e7\n"G': 1e8} set K and G without a word.
    out << toml_quoted(key) << " = ";
    const py::array_t<double, py::array::c_style | py::array::forcecast> a =
        py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
    if (!a)
      throw InputError(std::string(what) + ": '" + key +
                       "' must be a number or an array of numbers");
    if (a.ndim() == 0) {
      out << toml_number(*a.data());
    } else if (a.ndim() == 2) {
      out << '[';
      for (py::ssize_t i = 0; i < a.shape(0); ++i) {
        out << (i ? ", [" : "[");
        for (py::ssize_t j = 0; j < a.shape(1); ++j)
          out << (j ? ", " : "") << toml_number(a.at(i, j));
        out << ']';
      }
      out << ']';
    } else {
      // The wrapper's message for values that are not numbers, with the shape given.
      std::ostringstream msg;
      msg << what << ": '" << key
          << "' must be a number or a 3x3 array of numbers, got an array of shape (";
      for (py::ssize_t i = 0; i < a.ndim(); ++i) msg << (i ? ", " : "") << a.shape(i);
      msg << (a.ndim() == 1 ? ",)" : ")");
      throw InputError(msg.str());
    }
    out << '\n';
  }
  return out.str();
}

// Parameters or a state given as a dictionary (TOML text) or as the path of a TOML file. `what`
// names the argument, `content` its values as the readers name them (parameters: 'K' ...).
std::pair<std::string, bool> toml_input(const py::object& x, const char* what,
                                        const char* content) {
  if (x.is_none()) return {"", false};
  if (py::isinstance<py::dict>(x)) return {toml_of(x.cast<py::dict>(), content), true};
  if (py::isinstance<py::str>(x) || py::hasattr(x, "__fspath__")) {
    std::string path = py::str(py::module_::import("os").attr("fspath")(x));
    // "" stands for no file inside; params="" took the law's defaults without a word.
    if (path.empty()) throw InputError(std::string(what) + ": the file name is empty");
    return {path, false};
  }
  throw InputError("expected a dictionary or the path of a TOML file");
}

// A law's parameters (toml_input). A UMAT's come from a file only (props of any length, names,
// [bounds]: docs/umat.md); a dictionary is left for app::law_for to refuse in its own words,
// before toml_of would stumble on the props' length.
std::pair<std::string, bool> params_input(const std::string& model, const py::object& params) {
  if (model == "umat" && py::isinstance<py::dict>(params)) return {"", true};
  return toml_input(params, "params", "parameters");
}

std::vector<std::string> sets_of(const py::object& sets) {
  std::vector<std::string> out;
  if (sets.is_none()) return out;
  if (py::isinstance<py::dict>(sets)) {
    // A value as the scenario's TOML spells it: text quoted, lists bracketed, booleans lower.
    // numpy's scalars and arrays as Python's own numbers and lists (json knows no np.int64).
    const py::object json = py::module_::import("json");
    for (const auto& [k, v] : sets.cast<py::dict>()) {
      py::object plain = py::reinterpret_borrow<py::object>(v);
      if (py::hasattr(plain, "tolist")) plain = plain.attr("tolist")();
      std::string text;
      try {
        text = py::str(json.attr("dumps")(plain));
      } catch (py::error_already_set&) {
        throw py::type_error("sets: the value of '" + std::string(py::str(k)) +
                             "' is not a number, a text, a boolean or a list of them");
      }
      out.push_back(std::string(py::str(k)) + "=" + text);
    }
    return out;
  }
  // A text is a sequence too: "k=v" would be cast letter by letter.
  if (!py::isinstance<py::str>(sets) && py::isinstance<py::sequence>(sets)) try {
      return sets.cast<std::vector<std::string>>();
    } catch (const py::cast_error&) {
    }
  throw py::type_error("sets: expected a dict {key: value} or a list of 'key=value' texts");
}

std::vector<Eigen::Vector2d> points_of(const py::object& x, const char* what) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(x);
  if (!a || a.ndim() != 2 || a.shape(1) != 2)
    throw InputError(std::string(what) + ": expected an array of shape [n, 2]");
  std::vector<Eigen::Vector2d> out(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) out[i] = {a.at(i, 0), a.at(i, 1)};
  return out;
}

// The end of a material-point path: a strain tensor (symmetric 3x3, compression positive) for
// kind "proportional", else a number.
double end_number(const py::object& end, const std::string& kind) {
  try {
    return end.cast<double>();  // numpy's scalars and 0-d arrays too
  } catch (const py::cast_error&) {
    PyErr_Clear();
    throw InputError("end: the end strain of kind '" + kind +
                     "' is a number (a strain tensor is for kind 'proportional')");
  }
}
Eigen::Matrix3d end_tensor(const py::object& end) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(end);
  if (!a || a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
    throw InputError("end: the end of a proportional path is a 3x3 strain tensor");
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = a.at(i, j);
  // As a state's tensors (material_io.cpp): an asymmetric strain is a typo, not a rotation.
  if (m.allFinite() && (m - m.transpose()).norm() > 1e-12 * m.norm())
    throw InputError("end: the end strain must be a symmetric 3x3 tensor");
  return m;
}

// A count taken from Python as a 64-bit integer and narrowed here: pybind's own refusal of an
// int beyond 32 bits (directions=2**31) is a TypeError that lists every signature and names no
// argument. Within 32 bits the count's own range is checked where it is used.
int count_of(long long v, const char* name) {
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
    throw InputError(std::string(name) + " = " + std::to_string(v) + " is out of range");
  return static_cast<int>(v);
}

py::dict model_envelope_dict(const EnvelopeRecord& env, const std::string& law_name) {
  py::dict d;
  d["model"] = law_name;
  d["theta_deg"] = array_of(env.theta_deg);
  d["strain"] = pairs_of(env.strain);
  d["stress"] = pairs_of(env.stress);
  d["fabric"] = pairs_of(env.fabric);
  d["d_stress"] = tensors_of(env.d_stress);
  d["d_fabric"] = tensors_of(env.d_fabric);
  d["max_error_estimate"] = env.attributes.at("max_error_estimate");
  d["within_tolerance"] = env.attributes.at("within_tolerance") != 0.0;
  d["total_substeps"] = static_cast<int>(env.attributes.at("total_substeps"));
  return d;
}

}  // namespace
}  // namespace rendulic::python

PYBIND11_MODULE(_rendulic, m) {
  using namespace rendulic;
  using namespace rendulic::python;
  m.doc() = "rendulic's C++ core (docs/python.md); use the package `rendulic`";
  log::keep_standard_streams_open();  // before any file of ours is opened (log.hpp)

  // The library's tidying-up on fatal signals (temporary results files removed, completed
  // stages kept) is wanted, but SIGINT stays Python's: it becomes KeyboardInterrupt, and the
  // C++ side unwinds as for any error, which tidies up the same files.
  {
    struct sigaction python_int {};
    ::sigaction(SIGINT, nullptr, &python_int);
    cleanup::install_handlers();
    ::sigaction(SIGINT, &python_int, nullptr);
  }
  calibration::quiet_solver_logging();  // before any thread of ours (solver.hpp)

  // The message is the CLI's line after "rendulic: " (main.cpp prints it through printable()).
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(printable(e.what()).c_str());
    }
  });

  py::class_<Reader>(m, "_Reader")
      .def(py::init<const std::string&>(), "path"_a)
      .def_property_readonly("path", &Reader::path)
      .def("children", &Reader::children, "group"_a)
      .def("attrs", &Reader::attrs, "object"_a)
      .def("read", &Reader::read, "path"_a)
      .def("states", &Reader::states, "root"_a = "")
      .def("state", &Reader::state, "label"_a, "root"_a = "")
      .def("envelopes", &Reader::envelopes, "label"_a, "root"_a = "")
      .def("envelope", &Reader::envelope, "label"_a, "name"_a, "root"_a = "")
      .def("series", &Reader::series, "group"_a)
      .def("branches", &Reader::branches)
      .def("calibration", &Reader::calibration);

  // The driver's default local error tolerance (models/driver.hpp), the Python defaults' too.
  m.attr("DEFAULT_TOLERANCE") = models::StepOptions{}.tolerance;
  m.def("fit_shape_choices", &fit_shape_choices);
  m.def("fit_loss_choices", &fit_loss_choices);
  m.def("law_names", &models::law_names);
  m.def("probe_methods",
        [] { return std::vector<std::string>(kProbeMethods.begin(), kProbeMethods.end()); });
  // A method the stages never write read as no envelope at all; refused in the CLI's words.
  m.def("check_probe_method", [](const std::string& method) {
    if (const std::string why = choice_refusal(method, kProbeMethods); !why.empty())
      throw InputError("method: " + why);
  });

  m.def(
      "fit_envelope",
      [](const py::object& points, const py::object& theta_deg, const py::object& strain,
         double amplitude, const std::string& shape, const std::string& loss, double loss_scale,
         bool use_theta) {
        Envelope env;
        env.response = points_of(points, "points");
        if (!theta_deg.is_none()) {
          const auto t =
              py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(theta_deg);
          if (!t || t.ndim() != 1)
            throw InputError("theta_deg: expected a sequence of numbers (degrees)");
          env.theta_deg.assign(t.data(), t.data() + t.size());
        }
        if (!strain.is_none()) env.strain = points_of(strain, "strain");
        env.amplitude = amplitude;
        FitOptions o;
        o.shape = fit_shape_from_string(shape);
        o.loss = fit_loss_from_string(loss);
        o.loss_scale = loss_scale;
        o.use_theta = use_theta;
        EnvelopeFit f;
        {
          py::gil_scoped_release release;
          f = fit_envelope(env, o);
        }
        return fit_dict(f);
      },
      "points"_a, "theta_deg"_a = py::none(), "strain"_a = py::none(), "amplitude"_a = 0.0,
      "shape"_a = "auto", "loss"_a = "none", "loss_scale"_a = 0.0, "use_theta"_a = true);

  m.def(
      "model_envelope",
      [](const std::string& model, const py::object& state, const py::object& params,
         double amplitude, long long directions, const std::string& method,
         const std::string& scheme, double tolerance, long long substeps, const std::string& umat) {
        app::EnvelopeRequest r;
        r.model = model;
        r.umat = umat;
        std::tie(r.params, r.params_is_text) = params_input(model, params);
        std::tie(r.state, r.state_is_text) = toml_input(state, "state", "state");
        if (r.state.empty() && !r.state_is_text) throw InputError("a state is required");
        r.amplitude = amplitude;
        r.directions = count_of(directions, "directions");
        r.method = method;
        r.scheme = scheme;
        r.tolerance = tolerance;
        r.substeps = count_of(substeps, "substeps");
        std::string name;
        EnvelopeRecord env;
        {
          py::gil_scoped_release release;
          env = app::envelope_for(r, &name);
        }
        return model_envelope_dict(env, name);
      },
      "model"_a, "state"_a, "params"_a = py::none(), "amplitude"_a = 5e-5, "directions"_a = 36,
      "method"_a = "integrated", "scheme"_a = "modified-euler",
      "tolerance"_a = models::StepOptions{}.tolerance, "substeps"_a = 1, "umat"_a = "");

  m.def(
      "material_point_path",
      [](const std::string& model, const py::object& state, const py::object& params,
         const std::string& kind, const py::object& end, long long steps, const std::string& scheme,
         double tolerance, long long substeps, const std::string& umat,
         const py::object& progress) {
        const auto [p, p_text] = params_input(model, params);
        const auto [s, s_text] = toml_input(state, "state", "state");
        constexpr std::array<const char*, 4> kinds = {"undrained", "isotropic", "drained",
                                                      "proportional"};
        if (const std::string why = choice_refusal(kind, kinds); !why.empty())
          throw InputError("kind: " + why);
        const bool proportional = kind == "proportional";
        const Eigen::Matrix3d end_strain = proportional ? end_tensor(end) : Eigen::Matrix3d::Zero();
        const double end_value = proportional ? 0.0 : end_number(end, kind);
        models::PathOptions o;
        o.steps = count_of(steps, "steps");
        o.step = app::step_options_for(scheme, tolerance, count_of(substeps, "substeps"));
        std::string why;
        if (!o.IsValid(&why)) throw InputError("path options: " + why);
        // A path may take minutes (elastoplastic_fabric far below its stress scale, docs/
        // models.md "Paths"): Ctrl-C and the progress callback are heard after each step, at
        // most every app::kObserveEvery seconds and at the end. This call holds no process-wide
        // state (unlike run and probe), so paths in several threads still run at once.
        PendingError pending;
        struct Stopped {};
        using Clock = std::chrono::steady_clock;
        Clock::time_point last{};
        const std::string task = kind + " path of " + model;
        o.after_step = [&](int done, int total) {
          const Clock::time_point now = Clock::now();
          if (done < total &&
              std::chrono::duration<double>(now - last).count() < app::kObserveEvery)
            return;
          last = now;
          if (!tell_python(pending, progress, "path", task, double(done) / total)) throw Stopped{};
        };
        models::PathSeries series;
        try {
          py::gil_scoped_release release;
          const auto law = app::law_for(model, umat, p, p_text);
          const models::MaterialState start = app::state_for(*law, s, s_text);
          if (kind == "undrained")
            series = models::undrained_axisymmetric_path(*law, start, end_value, o);
          else if (kind == "drained")
            series = models::drained_triaxial_path(*law, start, end_value, o);
          else if (proportional)
            series = models::strain_path(*law, start, end_strain, o);
          else
            series = models::isotropic_compression_path(*law, start, end_value, o);
        } catch (const Stopped&) {
        }
        if (pending.set()) pending.raise();
        if (!series.success) throw InputError(kind + " path of " + model + ": " + series.reason);
        py::dict d;
        d["strain"] = tensors_of(series.strain);
        d["stress"] = tensors_of(series.stress);
        d["fabric"] = tensors_of(series.fabric);
        d["eps_v"] = array_of(series.eps_v);
        d["eps_dev"] = array_of(series.eps_dev);
        d["volume_fraction"] = array_of(series.volume_fraction);
        d["max_error_estimate"] = series.max_error_estimate;
        d["total_substeps"] = series.total_substeps;
        return d;
      },
      "model"_a, "state"_a, "params"_a = py::none(), "kind"_a = "undrained", "end"_a = -0.05,
      "steps"_a = 200, "scheme"_a = "modified-euler",
      "tolerance"_a = models::StepOptions{}.tolerance, "substeps"_a = 1, "umat"_a = "",
      "progress"_a = py::none());

  m.def(
      "probe",
      [](const std::string& packing, const std::string& out, const std::string& label,
         const std::vector<std::string>& methods, const std::vector<double>& amplitudes,
         long long directions, const std::vector<std::string>& planes, const py::object& sets,
         long long threads, bool quiet, const py::object& progress, bool leave_saddle) {
        app::ProbeRequest r;
        r.packing = packing;
        r.out = out;
        r.label = label;
        r.methods = methods;
        r.amplitudes = amplitudes;
        r.directions = count_of(directions, "directions");
        r.planes = planes;
        r.sets = sets_of(sets);
        r.threads = count_of(threads, "threads");
        r.quiet = quiet;
        r.leave_saddle = leave_saddle;
        r.summary = false;  // the caller has the file
        return long_work(progress, quiet, [&] { return app::probe_packing(r).string(); });
      },
      "packing"_a, "out"_a, "label"_a = "imported", "methods"_a = std::vector<std::string>{},
      "amplitudes"_a = std::vector<double>{}, "directions"_a = 0,
      "planes"_a = std::vector<std::string>{}, "sets"_a = py::none(), "threads"_a = 0,
      "quiet"_a = false, "progress"_a = py::none(), "leave_saddle"_a = false);

  m.def(
      "run",
      [](const std::string& scenario, const std::string& out, const py::object& sets,
         long long threads, bool quiet, bool resume, const py::object& progress) {
        app::RunRequest r;
        r.scenario = scenario;
        r.out = out;
        r.sets = sets_of(sets);
        r.threads = count_of(threads, "threads");
        r.quiet = quiet;
        r.resume = resume;
        return long_work(progress, quiet, [&] { return app::run_scenario(r).string(); });
      },
      "scenario"_a, "out"_a, "sets"_a = py::none(), "threads"_a = 0, "quiet"_a = false,
      "resume"_a = false, "progress"_a = py::none());
}
