// Atomic HDF5 results files, schema "rendulic/1" (interfaces.md "Results file"). See
// results.hpp. Implementation notes:
// - HDF5's automatic error stack printing is switched off: every failure becomes one
//   exception with one line, which the CLI turns into exit code 2 (input) or 1 (bug).
// - The temporary file lives in the destination folder so that the final rename is atomic
//   (same file system). SIGINT/SIGTERM remove live temporary files before the process dies,
//   so an interrupted run leaves neither results.h5 nor litter.
// - Series are chunked with an unlimited first dimension; 64 rows a chunk keeps appends
//   cheap without bloating short series.
#include "rendulic/core/results.hpp"

#include <H5Cpp.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/version.hpp"

namespace rendulic {
namespace fs = std::filesystem;
namespace {

constexpr hsize_t kChunkRows = 64;

void quiet_hdf5() {
  static const bool done = [] {
    H5::Exception::dontPrint();
    return true;
  }();
  (void)done;
}

// --- removal of temporary files on SIGINT / SIGTERM -------------------------------------
// A fixed table of C strings: the handler may only call async-signal-safe functions, so it
// uses unlink() on pre-formatted paths and never allocates.
constexpr int kSlots = 16;
std::array<std::array<char, 4096>, kSlots> g_tmp_paths{};
std::array<std::atomic<bool>, kSlots> g_tmp_used{};

extern "C" void remove_temporaries_and_die(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_tmp_used[i].load()) ::unlink(g_tmp_paths[i].data());
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

int register_temporary(const fs::path& p) {
  static const bool installed = [] {
    std::signal(SIGINT, remove_temporaries_and_die);
    std::signal(SIGTERM, remove_temporaries_and_die);
    return true;
  }();
  (void)installed;
  const std::string s = p.string();
  if (s.size() >= 4096) return -1;
  for (int i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (!g_tmp_used[i].load()) {
      std::memcpy(g_tmp_paths[i].data(), s.c_str(), s.size() + 1);
      if (g_tmp_used[i].compare_exchange_strong(expected, true)) return i;
    }
  }
  return -1;
}

void unregister_temporary(int slot) {
  if (slot >= 0) g_tmp_used[slot].store(false);
}

// --- small HDF5 helpers ---------------------------------------------------------------
std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string part; std::getline(ss, part, '/');)
    if (!part.empty()) parts.push_back(part);
  return parts;
}

bool link_exists(const H5::H5File& f, const std::string& path) {
  // H5Lexists fails on a missing intermediate link, so check each prefix in turn.
  std::string prefix;
  for (const auto& part : split_path(path)) {
    prefix += "/" + part;
    if (H5Lexists(f.getId(), prefix.c_str(), H5P_DEFAULT) <= 0) return false;
  }
  return true;
}

H5::Group ensure_group(H5::H5File& f, const std::string& path) {
  std::string prefix;
  for (const auto& part : split_path(path)) {
    prefix += "/" + part;
    if (H5Lexists(f.getId(), prefix.c_str(), H5P_DEFAULT) <= 0) f.createGroup(prefix);
  }
  return f.openGroup(prefix.empty() ? "/" : prefix);
}

std::string parent_of(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos || slash == 0 ? "/" : path.substr(0, slash);
}

H5::StrType string_type() { return H5::StrType(H5::PredType::C_S1, H5T_VARIABLE); }

}  // namespace

// ========================================================================================
struct ResultsWriter::Impl {
  fs::path final_path, tmp_path;
  // Constructed in place: HDF5 1.10's implicit H5File copy-assignment copies the id without
  // taking a reference, so assigning a temporary would close the file under us.
  std::optional<H5::H5File> holder;
  int slot = -1;
  bool committed = false;

  // Runs `fn` on the object at `object` (a dataset if one exists there, else a group that is
  // created on demand).
  template <class Fn>
  void on_object(const std::string& object, Fn&& fn) {
    if (object != "/" && link_exists(*holder, object) &&
        holder->childObjType(object) == H5O_TYPE_DATASET) {
      H5::DataSet ds = holder->openDataSet(object);
      fn(static_cast<H5::H5Object&>(ds));
    } else {
      H5::Group g = ensure_group(*holder, object);
      fn(static_cast<H5::H5Object&>(g));
    }
  }

  void write_attr(const std::string& object, const std::string& name, const H5::DataType& type,
                  const H5::DataSpace& space, const void* data, bool is_string = false,
                  const std::string* str = nullptr) {
    on_object(object, [&](H5::H5Object& obj) {
      if (obj.attrExists(name)) obj.removeAttr(name);
      H5::Attribute a = obj.createAttribute(name, type, space);
      if (is_string)
        a.write(type, *str);
      else
        a.write(type, data);
    });
  }

  void write_dataset(const std::string& path, const std::vector<hsize_t>& dims,
                     const double* data) {
    ensure_group(*holder, parent_of(path));
    if (link_exists(*holder, path)) holder->unlink(path);
    H5::DataSpace space(static_cast<int>(dims.size()), dims.data());
    H5::DataSet ds = holder->createDataSet(path, H5::PredType::NATIVE_DOUBLE, space);
    ds.write(data, H5::PredType::NATIVE_DOUBLE);
  }

  // One row of shape `row` (empty = scalar) appended to a growable dataset.
  void append_row(const std::string& path, const std::vector<hsize_t>& row, const double* data) {
    const int rank = static_cast<int>(row.size()) + 1;
    std::vector<hsize_t> dims(rank), maxdims(rank), chunk(rank);
    dims[0] = 0, maxdims[0] = H5S_UNLIMITED, chunk[0] = kChunkRows;
    for (std::size_t i = 0; i < row.size(); ++i)
      dims[i + 1] = maxdims[i + 1] = chunk[i + 1] = row[i];
    auto open_or_create = [&]() -> H5::DataSet {
      if (link_exists(*holder, path)) return holder->openDataSet(path);
      ensure_group(*holder, parent_of(path));
      H5::DSetCreatPropList plist;
      plist.setChunk(rank, chunk.data());
      H5::DataSpace space(rank, dims.data(), maxdims.data());
      return holder->createDataSet(path, H5::PredType::NATIVE_DOUBLE, space, plist);
    };
    H5::DataSet ds = open_or_create();
    H5::DataSpace cur = ds.getSpace();
    if (cur.getSimpleExtentNdims() != rank)
      throw std::logic_error("append to " + path + ": row shape differs from the series");
    std::vector<hsize_t> size(rank);
    cur.getSimpleExtentDims(size.data());
    const hsize_t n = size[0];
    size[0] = n + 1;
    ds.extend(size.data());
    H5::DataSpace fspace = ds.getSpace();
    std::vector<hsize_t> start(rank, 0), count(rank);
    start[0] = n, count[0] = 1;
    for (std::size_t i = 0; i < row.size(); ++i) count[i + 1] = row[i];
    fspace.selectHyperslab(H5S_SELECT_SET, count.data(), start.data());
    H5::DataSpace mspace(rank, count.data());
    ds.write(data, H5::PredType::NATIVE_DOUBLE, mspace, fspace);
  }
};

namespace {
fs::path temporary_for(const fs::path& final_path) {
  // Built with append rather than operator+ chains: GCC 12 reports a false -Wrestrict there.
  std::string name = ".";
  name.append(final_path.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  return final_path.parent_path() / name;
}

std::string h5_reason(const H5::Exception& e) {
  std::string r = e.getDetailMsg();
  return r.empty() ? std::string("HDF5 error") : r;
}
}  // namespace

ResultsWriter::ResultsWriter(const fs::path& final_path) : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  impl_->final_path = final_path;
  std::error_code ec;
  if (!final_path.parent_path().empty()) fs::create_directories(final_path.parent_path(), ec);
  if (ec)
    throw InputError(final_path.parent_path().string() +
                     ": cannot create output folder: " + ec.message());
  impl_->tmp_path = temporary_for(final_path);
  impl_->slot = register_temporary(impl_->tmp_path);
  try {
    impl_->holder.emplace(impl_->tmp_path.string(), H5F_ACC_TRUNC);
  } catch (const H5::Exception& e) {
    unregister_temporary(impl_->slot);
    throw InputError(impl_->tmp_path.string() + ": cannot create results file: " + h5_reason(e));
  }
  attr("/", "schema", kSchema);
  attr("/", "version", kVersion);
  attr("/", "git_sha", kGitSha);
}

ResultsWriter ResultsWriter::update(const fs::path& existing_path) {
  quiet_hdf5();
  { ResultsReader check(existing_path); }  // refuses files that are not ours
  ResultsWriter w;
  w.impl_ = std::make_unique<Impl>();
  w.impl_->final_path = existing_path;
  w.impl_->tmp_path = temporary_for(existing_path);
  w.impl_->slot = register_temporary(w.impl_->tmp_path);
  std::error_code ec;
  fs::copy_file(existing_path, w.impl_->tmp_path, fs::copy_options::overwrite_existing, ec);
  if (ec) {
    unregister_temporary(w.impl_->slot);
    throw InputError(existing_path.string() + ": cannot copy for update: " + ec.message());
  }
  try {
    w.impl_->holder.emplace(w.impl_->tmp_path.string(), H5F_ACC_RDWR);
  } catch (const H5::Exception& e) {
    fs::remove(w.impl_->tmp_path, ec);
    unregister_temporary(w.impl_->slot);
    throw InputError(existing_path.string() + ": cannot open for update: " + h5_reason(e));
  }
  return w;
}

ResultsWriter::ResultsWriter(ResultsWriter&&) noexcept = default;
ResultsWriter& ResultsWriter::operator=(ResultsWriter&&) noexcept = default;

ResultsWriter::~ResultsWriter() {
  if (!impl_ || impl_->committed) return;
  try {
    impl_->holder->close();
  } catch (...) {
  }
  std::error_code ec;
  fs::remove(impl_->tmp_path, ec);
  unregister_temporary(impl_->slot);
}

void ResultsWriter::attr(const std::string& object, const std::string& name, double value) {
  impl_->write_attr(object, name, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(H5S_SCALAR), &value);
}
void ResultsWriter::attr(const std::string& object, const std::string& name, std::int64_t value) {
  impl_->write_attr(object, name, H5::PredType::NATIVE_INT64, H5::DataSpace(H5S_SCALAR), &value);
}
void ResultsWriter::attr(const std::string& object, const std::string& name,
                         const std::string& value) {
  impl_->write_attr(object, name, string_type(), H5::DataSpace(H5S_SCALAR), nullptr, true, &value);
}
void ResultsWriter::attr(const std::string& object, const std::string& name, const char* value) {
  attr(object, name, std::string(value));
}
void ResultsWriter::attr(const std::string& object, const std::string& name,
                         const std::vector<double>& value) {
  const hsize_t n = value.size();
  impl_->write_attr(object, name, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(1, &n), value.data());
}

void ResultsWriter::write(const std::string& path, const std::vector<double>& values) {
  impl_->write_dataset(path, {values.size()}, values.data());
}
void ResultsWriter::write(const std::string& path, const std::vector<Eigen::Vector2d>& pairs) {
  std::vector<double> flat;
  flat.reserve(2 * pairs.size());
  for (const auto& p : pairs) flat.insert(flat.end(), {p.x(), p.y()});
  impl_->write_dataset(path, {pairs.size(), 2}, flat.data());
}
void ResultsWriter::write(const std::string& path, const std::vector<Eigen::Matrix3d>& tensors) {
  std::vector<double> flat;
  flat.reserve(9 * tensors.size());
  for (const auto& t : tensors)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) flat.push_back(t(i, j));
  impl_->write_dataset(path, {tensors.size(), 3, 3}, flat.data());
}
void ResultsWriter::write(const std::string& path, const Eigen::Matrix3d& tensor) {
  write(path, Eigen::MatrixXd(tensor));
}
void ResultsWriter::write(const std::string& path, const Eigen::MatrixXd& matrix) {
  // HDF5 is row-major; Eigen's default is column-major.
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = matrix;
  impl_->write_dataset(path, {static_cast<hsize_t>(rm.rows()), static_cast<hsize_t>(rm.cols())},
                       rm.data());
}

void ResultsWriter::append(const std::string& path, double value) {
  impl_->append_row(path, {}, &value);
}
void ResultsWriter::append(const std::string& path, const Eigen::Vector2d& pair) {
  impl_->append_row(path, {2}, pair.data());
}
void ResultsWriter::append(const std::string& path, const Eigen::Matrix3d& tensor) {
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> rm = tensor;
  impl_->append_row(path, {3, 3}, rm.data());
}

void ResultsWriter::create_group(const std::string& path) { ensure_group(*impl_->holder, path); }

void ResultsWriter::commit() {
  if (impl_->committed) throw std::logic_error("ResultsWriter::commit called twice");
  impl_->holder->flush(H5F_SCOPE_GLOBAL);
  impl_->holder->close();
  std::error_code ec;
  fs::rename(impl_->tmp_path, impl_->final_path, ec);
  if (ec) {
    fs::remove(impl_->tmp_path);
    unregister_temporary(impl_->slot);
    impl_->committed = true;
    throw InputError(impl_->final_path.string() +
                     ": cannot move results into place: " + ec.message());
  }
  unregister_temporary(impl_->slot);
  impl_->committed = true;
}

const fs::path& ResultsWriter::final_path() const { return impl_->final_path; }
const fs::path& ResultsWriter::temporary_path() const { return impl_->tmp_path; }

// ========================================================================================
struct ResultsReader::Impl {
  fs::path path;
  std::optional<H5::H5File> holder;  // in place, see ResultsWriter::Impl

  void require(const std::string& object) const {
    if (!link_exists(*holder, object))
      throw InputError(path.string() + ": no '" + object + "' in results file");
  }
  H5::Attribute open_attr(const std::string& object, const std::string& name) const {
    if (object != "/") require(object);
    if (object != "/" && holder->childObjType(object) == H5O_TYPE_DATASET) {
      H5::DataSet ds = holder->openDataSet(object);
      if (!ds.attrExists(name))
        throw InputError(path.string() + ": no attribute '" + name + "' on " + object);
      return ds.openAttribute(name);
    }
    H5::Group g = holder->openGroup(object);
    if (!g.attrExists(name))
      throw InputError(path.string() + ": no attribute '" + name + "' on " + object);
    return g.openAttribute(name);
  }
  // A dataset's doubles (converted by HDF5 from whatever numeric type it is stored as).
  std::vector<double> read_all(const std::string& p, std::vector<hsize_t>* dims) const {
    require(p);
    H5::DataSet ds = holder->openDataSet(p);
    H5::DataSpace space = ds.getSpace();
    std::vector<hsize_t> d(space.getSimpleExtentNdims());
    space.getSimpleExtentDims(d.data());
    hsize_t n = 1;
    for (auto x : d) n *= x;
    std::vector<double> data(n);
    if (n) ds.read(data.data(), H5::PredType::NATIVE_DOUBLE);
    if (dims) *dims = d;
    return data;
  }
  void expect_shape(const std::string& p, const std::vector<hsize_t>& d,
                    std::initializer_list<long> tail) const {
    bool ok = d.size() == tail.size() + 1;
    std::size_t i = 1;
    for (long t : tail) ok = ok && i < d.size() && d[i++] == static_cast<hsize_t>(t);
    if (!ok) throw InputError(path.string() + ": dataset " + p + " has an unexpected shape");
  }
};

ResultsReader::ResultsReader(const fs::path& path) : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  impl_->path = path;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path.string() + ": no such file");
  bool is_h5 = false;
  try {
    is_h5 = H5::H5File::isHdf5(path.string());
  } catch (const H5::Exception&) {
    is_h5 = false;
  }
  if (!is_h5) throw InputError(path.string() + ": not an HDF5 file");
  try {
    impl_->holder.emplace(path.string(), H5F_ACC_RDONLY);
  } catch (const H5::Exception& e) {
    throw InputError(path.string() + ": cannot open (corrupt HDF5 file?): " + h5_reason(e));
  }
  std::string schema;
  try {
    schema = attr_string("/", "schema");
  } catch (const std::exception&) {
    throw InputError(path.string() + ": not a rendulic results file (no schema attribute)");
  }
  if (schema != kSchema)
    throw InputError(path.string() + ": schema '" + schema + "' is not " + kSchema);
}

ResultsReader::ResultsReader(ResultsReader&&) noexcept = default;
ResultsReader::~ResultsReader() = default;

bool ResultsReader::exists(const std::string& path) const {
  return path == "/" || link_exists(*impl_->holder, path);
}

bool ResultsReader::has_attr(const std::string& object, const std::string& name) const {
  if (!exists(object)) return false;
  try {
    impl_->open_attr(object, name);
    return true;
  } catch (const InputError&) {
    return false;
  }
}

std::vector<std::string> ResultsReader::children(const std::string& group) const {
  std::vector<std::string> out;
  if (!exists(group)) return out;
  H5::Group g = impl_->holder->openGroup(group);
  for (hsize_t i = 0; i < g.getNumObjs(); ++i) out.push_back(g.getObjnameByIdx(i));
  return out;
}

double ResultsReader::attr_double(const std::string& object, const std::string& name) const {
  double v = 0;
  impl_->open_attr(object, name).read(H5::PredType::NATIVE_DOUBLE, &v);
  return v;
}
std::int64_t ResultsReader::attr_int(const std::string& object, const std::string& name) const {
  std::int64_t v = 0;
  impl_->open_attr(object, name).read(H5::PredType::NATIVE_INT64, &v);
  return v;
}
std::string ResultsReader::attr_string(const std::string& object, const std::string& name) const {
  H5::Attribute a = impl_->open_attr(object, name);
  if (a.getTypeClass() != H5T_STRING)
    throw InputError(impl_->path.string() + ": attribute " + name + " is not a string");
  std::string v;
  a.read(a.getStrType(), v);
  return v;
}
std::vector<double> ResultsReader::attr_doubles(const std::string& object,
                                                const std::string& name) const {
  H5::Attribute a = impl_->open_attr(object, name);
  const hssize_t n = a.getSpace().getSimpleExtentNpoints();
  std::vector<double> v(static_cast<std::size_t>(n));
  if (n) a.read(H5::PredType::NATIVE_DOUBLE, v.data());
  return v;
}

std::vector<std::uint64_t> ResultsReader::shape(const std::string& path) const {
  impl_->require(path);
  H5::DataSpace space = impl_->holder->openDataSet(path).getSpace();
  std::vector<hsize_t> d(space.getSimpleExtentNdims());
  space.getSimpleExtentDims(d.data());
  return {d.begin(), d.end()};
}

std::vector<double> ResultsReader::read_vector(const std::string& path) const {
  std::vector<hsize_t> d;
  auto data = impl_->read_all(path, &d);
  impl_->expect_shape(path, d, {});
  return data;
}
std::vector<Eigen::Vector2d> ResultsReader::read_pairs(const std::string& path) const {
  std::vector<hsize_t> d;
  auto data = impl_->read_all(path, &d);
  impl_->expect_shape(path, d, {2});
  std::vector<Eigen::Vector2d> out(d[0]);
  for (hsize_t i = 0; i < d[0]; ++i) out[i] = {data[2 * i], data[2 * i + 1]};
  return out;
}
std::vector<Eigen::Matrix3d> ResultsReader::read_tensors(const std::string& path) const {
  std::vector<hsize_t> d;
  auto data = impl_->read_all(path, &d);
  impl_->expect_shape(path, d, {3, 3});
  std::vector<Eigen::Matrix3d> out(d[0]);
  for (hsize_t n = 0; n < d[0]; ++n)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out[n](i, j) = data[9 * n + 3 * i + j];
  return out;
}
Eigen::Matrix3d ResultsReader::read_tensor(const std::string& path) const {
  const Eigen::MatrixXd m = read_matrix(path);
  if (m.rows() != 3 || m.cols() != 3)
    throw InputError(impl_->path.string() + ": dataset " + path + " is not 3x3");
  return m;
}
Eigen::MatrixXd ResultsReader::read_matrix(const std::string& path) const {
  std::vector<hsize_t> d;
  auto data = impl_->read_all(path, &d);
  if (d.size() != 2)
    throw InputError(impl_->path.string() + ": dataset " + path + " is not a matrix");
  Eigen::MatrixXd m(d[0], d[1]);
  for (hsize_t i = 0; i < d[0]; ++i)
    for (hsize_t j = 0; j < d[1]; ++j) m(i, j) = data[i * d[1] + j];
  return m;
}

const fs::path& ResultsReader::path() const { return impl_->path; }

namespace {
std::string attr_text(const H5::Attribute& a) {
  std::ostringstream out;
  const auto cls = a.getTypeClass();
  const hssize_t n = a.getSpace().getSimpleExtentNpoints();
  if (cls == H5T_STRING) {
    std::string s;
    a.read(a.getStrType(), s);
    const auto nl = s.find('\n');
    if (nl != std::string::npos || s.size() > 60)
      out << '"' << s.substr(0, std::min<std::size_t>(nl, 60)) << "...\" (" << s.size()
          << " chars)";
    else
      out << '"' << s << '"';
  } else if (cls == H5T_INTEGER || cls == H5T_FLOAT) {
    std::vector<double> v(static_cast<std::size_t>(n));
    if (n) a.read(H5::PredType::NATIVE_DOUBLE, v.data());
    if (n == 1)
      out << v[0];
    else {
      out << "[";
      for (hssize_t i = 0; i < std::min<hssize_t>(n, 6); ++i) out << (i ? ", " : "") << v[i];
      out << (n > 6 ? ", ...]" : "]");
    }
  } else {
    out << "(" << n << " values)";
  }
  return out.str();
}

void describe(const H5::H5File& f, const std::string& path, int depth, std::ostringstream& out) {
  const std::string indent(2 * depth, ' ');
  auto attrs = [&](H5::H5Object& obj) {
    for (int i = 0; i < obj.getNumAttrs(); ++i) {
      H5::Attribute a = obj.openAttribute(static_cast<unsigned>(i));
      out << indent << "  @" << a.getName() << " = " << attr_text(a) << "\n";
    }
  };
  H5::Group g = f.openGroup(path);
  out << indent << (path == "/" ? "/" : split_path(path).back() + "/") << "\n";
  attrs(g);
  for (hsize_t i = 0; i < g.getNumObjs(); ++i) {
    const std::string name = g.getObjnameByIdx(i);
    const std::string child = (path == "/" ? "" : path) + "/" + name;
    if (g.childObjType(name) == H5O_TYPE_GROUP) {
      describe(f, child, depth + 1, out);
    } else {
      H5::DataSet ds = f.openDataSet(child);
      H5::DataSpace space = ds.getSpace();
      std::vector<hsize_t> d(space.getSimpleExtentNdims());
      space.getSimpleExtentDims(d.data());
      out << indent << "  " << name << " [";
      for (std::size_t k = 0; k < d.size(); ++k) out << (k ? "," : "") << d[k];
      out << "]\n";
      attrs(ds);
    }
  }
}
}  // namespace

std::string ResultsReader::summary() const {
  std::ostringstream out;
  out << impl_->path.string() << " (" << kSchema << ")\n";
  try {
    describe(*impl_->holder, "/", 0, out);
  } catch (const H5::Exception& e) {
    throw InputError(impl_->path.string() + ": corrupt results file: " + h5_reason(e));
  }
  return out.str();
}

}  // namespace rendulic
