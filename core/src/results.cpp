// Atomic HDF5 results files, schema "rendulic/2" (docs/results.md,
// docs/usage.md "Results are atomic"). See results.hpp. Implementation notes:
// - HDF5's automatic error printing is replaced by a recorder (hdf5_reason.hpp): every
//   failure becomes one InputError line naming the file, the object and the reason.
// - The temporary file lives in the destination folder so that the final rename is atomic
//   (same file system). It is registered with cleanup.hpp, so a signal removes it, and the
//   saved copy of the completed stages becomes FINAL.partial instead.
// - A stale temporary file (its process is gone and nobody holds HDF5's lock on it) is
//   removed by the next writer in that folder; a stale saved copy is kept as FINAL.partial.
// - Series are chunked with an unlimited first dimension; 64 rows a chunk keeps appends
//   cheap without bloating short series.
#include "rendulic/core/results.hpp"

#include <H5Cpp.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>

#include "hdf5_reason.hpp"
#include "rendulic/core/cleanup.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/text_file.hpp"
#include "rendulic/core/version.hpp"

namespace rendulic {
namespace fs = std::filesystem;

namespace {

constexpr hsize_t kChunkRows = 64;

// --- small HDF5 helpers ---------------------------------------------------------------
std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string part; std::getline(ss, part, '/');)
    if (!part.empty()) parts.push_back(part);
  return parts;
}

// An object that can be opened at `path`: every link along it exists and the last one
// resolves (a dangling soft link does not).
bool link_exists(hid_t file, const std::string& path) {
  // H5Lexists fails on a missing intermediate link, so check each prefix in turn.
  std::string prefix;
  for (const auto& part : split_path(path)) {
    prefix += "/" + part;
    if (H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    if (H5Oexists_by_name(file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
  }
  return true;
}

H5O_type_t object_type(hid_t file, const std::string& path) {
  H5O_info_t info;
  if (H5Oget_info_by_name(file, path.c_str(), &info, H5P_DEFAULT) < 0) return H5O_TYPE_UNKNOWN;
  return info.type;
}

// The writer works with HDF5's C API: the C++ API's destructors print to stderr when a close
// fails, which is what closing does on a full disk. A Handle closes without a word; a failed
// call throws Failed, and the recorder of hdf5_reason.hpp holds why.
struct Failed {};

hid_t checked(hid_t id) {
  if (id < 0) throw Failed{};
  return id;
}

class Handle {
 public:
  explicit Handle(hid_t id) : id_(checked(id)) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(o.id_) { o.id_ = H5I_INVALID_HID; }
  ~Handle() {
    if (id_ >= 0) H5Idec_ref(id_);
  }
  hid_t get() const { return id_; }
  // Closes now, throwing Failed if that fails (a dataset's close writes its cached chunks).
  void close() {
    const hid_t id = id_;
    id_ = H5I_INVALID_HID;
    if (H5Idec_ref(id) < 0) throw Failed{};
  }

 private:
  hid_t id_;
};

// A path where a group must be and something else is (a damaged file being updated).
struct NotAGroup {
  std::string path;
};

Handle ensure_group(hid_t file, const std::string& path) {
  std::string prefix;
  for (const auto& part : split_path(path)) {
    prefix += "/" + part;
    if (H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0)
      Handle(H5Gcreate2(file, prefix.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)).close();
    else if (object_type(file, prefix) != H5O_TYPE_GROUP)
      throw NotAGroup{prefix};
  }
  return Handle(H5Gopen2(file, prefix.empty() ? "/" : prefix.c_str(), H5P_DEFAULT));
}

std::string parent_of(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos || slash == 0 ? "/" : path.substr(0, slash);
}

std::string shown(const std::string& s) { return printable(s); }

fs::path temporary_for(const fs::path& final_path) {
  // Built with append rather than operator+ chains: GCC 12 reports a false -Wrestrict there.
  std::string name = ".";
  name.append(final_path.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  return final_path.parent_path() / name;
}

fs::path with_suffix(const fs::path& p, const char* suffix) { return p.string() + suffix; }

// Copies a file, reporting the system's reason: std::filesystem::copy_file reports a copy cut
// short by a full disk as an "Input/output error".
std::string copy_whole_file(const fs::path& from, const fs::path& to) {
  const int in = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
  if (in < 0) return std::strerror(errno);
  const int out = ::open(to.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (out < 0) {
    const int e = errno;
    ::close(in);
    return std::strerror(e);
  }
  std::string why;
  std::vector<char> buf(1 << 16);
  for (;;) {
    const ssize_t n = ::read(in, buf.data(), buf.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      why = std::strerror(errno);
      break;
    }
    if (n == 0) break;
    for (ssize_t done = 0; done < n && why.empty();) {
      const ssize_t w = ::write(out, buf.data() + done, static_cast<std::size_t>(n - done));
      if (w < 0 && errno == EINTR) continue;
      if (w < 0)
        why = std::strerror(errno);
      else
        done += w;
    }
    if (!why.empty()) break;
  }
  if (::close(out) != 0 && why.empty()) why = std::strerror(errno);
  ::close(in);
  return why;
}

// What an flock of `operation` (LOCK_EX or LOCK_SH, not waiting) on the file meets: HDF5 1.10
// keeps an exclusive flock on a file while it writes it, a shared one while it reads it.
enum class FlockTry { kGranted, kHeldElsewhere, kCannotTry };
FlockTry try_flock(const fs::path& p, int operation) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return FlockTry::kCannotTry;
  FlockTry got = FlockTry::kGranted;
  if (::flock(fd, operation | LOCK_NB) != 0)
    got = errno == EWOULDBLOCK ? FlockTry::kHeldElsewhere : FlockTry::kCannotTry;
  ::close(fd);  // releases what was granted
  return got;
}

// Nobody has the file open through HDF5.
bool unlocked(const fs::path& p) { return try_flock(p, LOCK_EX) == FlockTry::kGranted; }

// Some process holds an exclusive flock on the file, as HDF5 does while it writes it.
bool locked_by_a_writer(const fs::path& p) {
  return try_flock(p, LOCK_SH) == FlockTry::kHeldElsewhere;
}

// Writers that replace a results file take an flock of its folder (advisory; no lock file is
// left behind, and HDF5's own flock is on the file itself). Two `calibrate`s of different laws
// at once each copied the file, added their law and renamed the copy back: the second rename
// dropped the first's law without a word. An update holds the lock from its copy to its rename;
// a writer of a new file takes it for its rename only, so that a run ending during an update
// lands after it. A process takes a folder's flock once, whatever number of its own writers
// hold it (a second flock through another descriptor would wait on the first for ever).
class FolderLock {
 public:
  explicit FolderLock(const fs::path& file) {
    const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
    std::error_code ec;
    key_ = fs::weakly_canonical(dir, ec).string();
    if (ec) key_ = dir.string();
    std::lock_guard<std::mutex> guard(mutex());
    Held& h = held()[key_];
    if (h.count++ > 0) return;
    h.fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (h.fd < 0) return;  // a folder we cannot open: no lock, as before
    if (::flock(h.fd, LOCK_EX | LOCK_NB) == 0) return;
    // A file system without locks (ENOLCK, EOPNOTSUPP): no lock, as for a folder we cannot
    // open; it said before that it waited for another process.
    if (errno != EWOULDBLOCK) return;
    log::info(file.string(), ": waiting for another rendulic process that is replacing a file ",
              "in its folder");
    while (::flock(h.fd, LOCK_EX) != 0 && errno == EINTR) {
    }
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  ~FolderLock() {
    std::lock_guard<std::mutex> guard(mutex());
    Held& h = held()[key_];
    if (--h.count > 0) return;
    if (h.fd >= 0) ::close(h.fd);  // closing the descriptor releases the flock
    held().erase(key_);
  }

 private:
  struct Held {
    int count = 0, fd = -1;
  };
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::map<std::string, Held>& held() {
    static std::map<std::string, Held> h;
    return h;
  }
  std::string key_;
};

}  // namespace

// One writer per results file in this process. Writers of one file share the temporary's
// name (.NAME.tmp-PID) and refuse_another_writer skips their own pid: two Python threads given
// one output both failed, the first on HDF5's "unable to truncate a file which is already
// open" and the second when the first's tidying removed the temporary it was writing.
class WriterClaim {
 public:
  explicit WriterClaim(const fs::path& final_path) {
    std::error_code ec;
    key_ = fs::weakly_canonical(fs::absolute(final_path, ec), ec).string();
    if (ec) key_ = fs::absolute(final_path).lexically_normal().string();
    std::lock_guard<std::mutex> guard(mutex());
    if (!claimed().insert(key_).second)
      throw InputError(final_path.string() +
                       ": another writer in this process (another thread) is writing this "
                       "file now; give each its own output");
  }
  WriterClaim(const WriterClaim&) = delete;
  WriterClaim& operator=(const WriterClaim&) = delete;
  ~WriterClaim() {
    std::lock_guard<std::mutex> guard(mutex());
    claimed().erase(key_);
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::set<std::string>& claimed() {
    static std::set<std::string> c;
    return c;
  }
  std::string key_;
};

// ========================================================================================
struct ResultsWriter::Impl {
  // Taken before anything in the folder is made or tidied, and given up after abandon().
  std::optional<WriterClaim> claim;
  fs::path final_path, tmp_path;
  fs::path partial_copy, partial_new;  // the saved copy of the completed stages, and its next
  std::string partial_completed;       // what the saved copy holds; empty: no copy
  std::optional<Handle> file;          // the open temporary file
  int tmp_handle = -1, partial_handle = -1, partial_new_handle = -1;
  bool committed = false;
  std::vector<fs::path> created_folders;  // innermost first, removed again if left empty
  std::vector<std::string> notes;
  std::optional<FolderLock> lock;  // an update's, from its copy to its rename (FolderLock)

  ~Impl() { abandon(); }

  hid_t id() const { return file->get(); }

  // A file HDF5 cannot close (a full disk) stays open in the library until the process ends.
  void close_quietly() { file.reset(); }

  // Without commit(): nothing half-written survives (keep_partial() has already moved the
  // saved copy if it is wanted).
  void abandon() {
    if (committed) return;
    close_quietly();
    std::error_code ec;
    for (const fs::path& p : {tmp_path, partial_new, partial_copy})
      if (!p.empty()) fs::remove(p, ec);
    for (int h : {tmp_handle, partial_handle, partial_new_handle}) cleanup::forget(h);
    tmp_handle = partial_handle = partial_new_handle = -1;
    for (const fs::path& d : created_folders) fs::remove(d, ec);  // fails unless empty
  }

  void make_folder() {
    const fs::path dir = final_path.parent_path();
    if (dir.empty()) return;
    created_folders = make_folders(dir, "output folder");
    std::error_code ec;
    // Found here, not at the rename after the last stage (the whole run's work then kept only
    // as FINAL.partial).
    if (fs::is_directory(final_path, ec))
      throw InputError(final_path.string() + ": is a folder (the results file is a file)");
  }

  // The temporary files of writers of final_path in its folder (ours and other processes'):
  // .NAME.tmp-PID, .NAME.tmp-PID.partial, .NAME.tmp-PID.partial-new.
  struct Temporary {
    fs::path path;
    std::string pid_text, suffix;
    long pid = 0;
    // That process still runs, or is not ours to judge.
    bool alive() const {
      return pid > 0 && pid <= 0x7fffffff &&
             (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH);
    }
    // That process has the file open. HDF5_USE_FILE_LOCKING=FALSE (common on cluster file
    // systems) leaves a writer's temporary without HDF5's flock; /proc says so of a process of
    // ours (another user's is not readable: false, and the flock alone decides).
    bool held_open() const {
      struct stat file {};
      if (::stat(path.c_str(), &file) != 0) return false;
      const fs::path fds = fs::path("/proc") / pid_text / "fd";
      std::error_code ec;
      for (fs::directory_iterator it(fds, ec), end; !ec && it != end; it.increment(ec)) {
        struct stat open {};
        if (::stat(it->path().c_str(), &open) == 0 && open.st_dev == file.st_dev &&
            open.st_ino == file.st_ino)
          return true;
      }
      return false;
    }
  };
  std::vector<Temporary> temporaries() const {
    const fs::path dir = final_path.has_parent_path() ? final_path.parent_path() : fs::path(".");
    const std::string prefix = "." + final_path.filename().string() + ".tmp-";
    std::vector<Temporary> found;
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (!name.starts_with(prefix)) continue;
      const std::string rest = name.substr(prefix.size());
      std::size_t k = 0;
      while (k < rest.size() && k < 10 && std::isdigit(static_cast<unsigned char>(rest[k]))) ++k;
      const std::string suffix = rest.substr(k);
      if (k == 0 || (suffix != "" && suffix != ".partial" && suffix != ".partial-new")) continue;
      found.push_back({it->path(), rest.substr(0, k), suffix, std::stol(rest.substr(0, k))});
    }
    return found;
  }

  // Temporary files of runs that were killed (SIGKILL, a power cut) before they could tidy.
  // Returns the listing it worked from (what it removed or renamed was never a live writer's).
  std::vector<Temporary> sweep_stale() {
    std::vector<Temporary> found = temporaries();
    for (const Temporary& t : found) {
      if (t.pid == ::getpid() || t.alive()) continue;
      if (t.suffix.empty() && !unlocked(t.path)) continue;  // open in a process we cannot see
      std::error_code rm;
      if (t.suffix == ".partial") {
        const fs::path kept = with_suffix(final_path, ".partial");
        if (!fs::exists(kept, rm)) {
          fs::rename(t.path, kept, rm);
          if (!rm) {
            notes.push_back(t.path.string() + ": the completed stages of a run that was killed " +
                            "(process " + t.pid_text + ") are kept in " + kept.string());
            continue;
          }
        }
      }
      fs::remove(t.path, rm);
      if (!rm)
        notes.push_back(t.path.string() + ": removed, a temporary file of a run that was killed " +
                        "(process " + t.pid_text + ")");
    }
    return found;
  }

  // A new results file at a path another live process is writing now (its temporary file
  // locked, as HDF5 keeps it, or open in that process): two runs into one --out would each finish,
  // the later one's file replacing the earlier's and their report.md and figures mixed in one
  // folder. Refused before anything is written. (An update, calibrate's, waits on FolderLock
  // instead.)
  void refuse_another_writer(const std::vector<Temporary>& listed) const {
    for (const Temporary& t : listed)
      if (t.suffix.empty() && t.pid != ::getpid() && t.alive() &&
          (!unlocked(t.path) || t.held_open()))
        throw InputError(final_path.string() + ": another rendulic process (pid " + t.pid_text +
                         ") is writing this file now; let it finish, or write elsewhere (--out)");
  }

  void check_names(const std::string& object, const std::string& attribute = {}) const {
    std::vector<std::string> parts = split_path(object);
    if (!attribute.empty()) parts.push_back(attribute);
    for (const auto& part : parts)
      if (const std::string why = invalid_object_name_reason(part); !why.empty())
        throw InputError(final_path.string() + ": cannot write " + shown(object) +
                         (attribute.empty() ? "" : " @" + shown(attribute)) + ": the name '" +
                         shown(part) + "' " + why);
  }

  // Runs `fn`, turning an HDF5 failure into one line naming the file and the object.
  template <class Fn>
  void guarded(const std::string& object, const std::string& attribute, Fn&& fn) {
    if (committed || !file) throw std::logic_error("ResultsWriter used after commit()");
    check_names(object, attribute);
    detail::forget_hdf5_reason();
    try {
      fn();
    } catch (const Failed&) {
      throw InputError(final_path.string() + ": cannot write " + shown(object) +
                       (attribute.empty() ? "" : " @" + shown(attribute)) + ": " +
                       detail::hdf5_reason());
    } catch (const NotAGroup& e) {
      throw InputError(final_path.string() + ": cannot write " + shown(object) +
                       (attribute.empty() ? "" : " @" + shown(attribute)) + ": " + shown(e.path) +
                       " is not a group");
    }
  }

  // Runs `fn` on the object at `object` (a dataset if one exists there, else a group that is
  // created on demand).
  template <class Fn>
  void on_object(const std::string& object, Fn&& fn) {
    if (object != "/" && link_exists(id(), object) &&
        object_type(id(), object) == H5O_TYPE_DATASET) {
      Handle ds(H5Dopen2(id(), object.c_str(), H5P_DEFAULT));
      fn(ds.get());
      ds.close();
    } else {
      Handle g = ensure_group(id(), object);
      fn(g.get());
      g.close();
    }
  }

  // One attribute; `space` and `type` are HDF5 ids, `data` what H5Awrite takes.
  void write_attr(const std::string& object, const std::string& name, hid_t type, hid_t space,
                  const void* data) {
    guarded(object, name, [&] {
      on_object(object, [&](hid_t obj) {
        if (H5Aexists(obj, name.c_str()) > 0) checked(H5Adelete(obj, name.c_str()));
        Handle a(H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT));
        checked(H5Awrite(a.get(), type, data));
        a.close();
      });
    });
  }

  void write_string_attr(const std::string& object, const std::string& name,
                         const std::string& value) {
    if (value.find('\0') != std::string::npos)
      throw InputError(final_path.string() + ": cannot write " + shown(object) + " @" + name +
                       ": the text holds a NUL character, which HDF5 strings cannot");
    guarded(object, name, [&] {
      Handle type(H5Tcopy(H5T_C_S1));
      checked(H5Tset_size(type.get(), H5T_VARIABLE));
      Handle space(H5Screate(H5S_SCALAR));
      const char* text = value.c_str();
      write_attr(object, name, type.get(), space.get(), &text);
    });
  }

  void write_string_array_attr(const std::string& object, const std::string& name,
                               const std::vector<std::string>& values) {
    for (const std::string& v : values)
      if (v.find('\0') != std::string::npos)
        throw InputError(final_path.string() + ": cannot write " + shown(object) + " @" + name +
                         ": the text holds a NUL character, which HDF5 strings cannot");
    guarded(object, name, [&] {
      Handle type(H5Tcopy(H5T_C_S1));
      checked(H5Tset_size(type.get(), H5T_VARIABLE));
      const hsize_t n = values.size();
      Handle space(H5Screate_simple(1, &n, nullptr));
      std::vector<const char*> texts;
      for (const std::string& v : values) texts.push_back(v.c_str());
      // An empty list is an attribute of no element (H5Awrite refuses a null buffer).
      static const char* const kNone = "";
      write_attr(object, name, type.get(), space.get(), texts.empty() ? &kNone : texts.data());
    });
  }

  // A new dataset's file type and unit (docs/results.md "Units"): counters are integers
  // (converted from the double buffer by HDF5), every other dataset float with its unit.
  static hid_t file_type_of(const std::string& path) {
    return units::is_counter(path) ? H5T_STD_I64LE : H5T_IEEE_F64LE;
  }
  void label_unit(hid_t dataset, const std::string& path) {
    const char* unit = units::is_counter(path) ? nullptr : units::of_dataset(path);
    if (!unit) return;
    Handle type(H5Tcopy(H5T_C_S1));
    checked(H5Tset_size(type.get(), H5T_VARIABLE));
    Handle space(H5Screate(H5S_SCALAR));
    Handle a(H5Acreate2(dataset, "units", type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
    checked(H5Awrite(a.get(), type.get(), &unit));
    a.close();
  }

  void write_dataset(const std::string& path, const std::vector<hsize_t>& dims,
                     const double* data) {
    guarded(path, {}, [&] {
      ensure_group(id(), parent_of(path)).close();
      if (H5Lexists(id(), path.c_str(), H5P_DEFAULT) > 0)
        checked(H5Ldelete(id(), path.c_str(), H5P_DEFAULT));
      Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
      Handle ds(H5Dcreate2(id(), path.c_str(), file_type_of(path), space.get(), H5P_DEFAULT,
                           H5P_DEFAULT, H5P_DEFAULT));
      label_unit(ds.get(), path);
      hsize_t n = 1;
      for (hsize_t d : dims) n *= d;
      if (n > 0)
        checked(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data));
      ds.close();
    });
  }

  // One row of shape `row` (empty = scalar) appended to a growable dataset.
  void append_row(const std::string& path, const std::vector<hsize_t>& row, const double* data) {
    guarded(path, {}, [&] {
      const int rank = static_cast<int>(row.size()) + 1;
      std::vector<hsize_t> dims(rank), maxdims(rank), chunk(rank);
      dims[0] = 0, maxdims[0] = H5S_UNLIMITED, chunk[0] = kChunkRows;
      for (std::size_t i = 0; i < row.size(); ++i)
        dims[i + 1] = maxdims[i + 1] = chunk[i + 1] = row[i];
      auto open_or_create = [&]() -> Handle {
        if (link_exists(id(), path)) return Handle(H5Dopen2(id(), path.c_str(), H5P_DEFAULT));
        ensure_group(id(), parent_of(path)).close();
        Handle plist(H5Pcreate(H5P_DATASET_CREATE));
        checked(H5Pset_chunk(plist.get(), rank, chunk.data()));
        Handle space(H5Screate_simple(rank, dims.data(), maxdims.data()));
        Handle ds(H5Dcreate2(id(), path.c_str(), file_type_of(path), space.get(), H5P_DEFAULT,
                             plist.get(), H5P_DEFAULT));
        label_unit(ds.get(), path);
        return ds;
      };
      Handle ds = open_or_create();
      std::vector<hsize_t> size(rank);
      {
        Handle cur(H5Dget_space(ds.get()));
        if (H5Sget_simple_extent_ndims(cur.get()) != rank)
          throw std::logic_error("append to " + path + ": row shape differs from the series");
        checked(H5Sget_simple_extent_dims(cur.get(), size.data(), nullptr));
      }
      const hsize_t n = size[0];
      size[0] = n + 1;
      checked(H5Dset_extent(ds.get(), size.data()));
      Handle fspace(H5Dget_space(ds.get()));
      std::vector<hsize_t> start(rank, 0), count(rank);
      start[0] = n, count[0] = 1;
      for (std::size_t i = 0; i < row.size(); ++i) count[i + 1] = row[i];
      checked(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                                  nullptr));
      Handle mspace(H5Screate_simple(rank, count.data(), nullptr));
      checked(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, mspace.get(), fspace.get(), H5P_DEFAULT, data));
      ds.close();
    });
  }

  void open(bool create, const std::string& what) {
    detail::forget_hdf5_reason();
    try {
      file.emplace(create ? H5Fcreate(tmp_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT)
                          : H5Fopen(tmp_path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    } catch (const Failed&) {
      throw InputError(final_path.string() + ": " + what + ": " + detail::hdf5_reason());
    }
  }
};

ResultsWriter::ResultsWriter(const fs::path& final_path) : impl_(std::make_unique<Impl>()) {
  detail::quiet_hdf5();
  Impl& m = *impl_;
  m.final_path = link_target(final_path);
  refuse_read_only(m.final_path, final_path, "the results file");
  m.claim.emplace(m.final_path);
  m.make_folder();
  m.refuse_another_writer(m.sweep_stale());
  m.tmp_path = temporary_for(m.final_path);
  m.tmp_handle = cleanup::remove_on_death(m.tmp_path);
  m.open(true, "cannot create results file");
  attr("/", "schema", kSchema);
  attr("/", "version", kVersion);
  attr("/", "git_sha", kGitSha);
}

ResultsWriter ResultsWriter::update(const fs::path& existing_path) {
  detail::quiet_hdf5();
  { ResultsReader check(existing_path); }  // refuses files that are not ours
  ResultsWriter w;
  w.impl_ = std::make_unique<Impl>();
  Impl& m = *w.impl_;
  m.final_path = link_target(existing_path);
  refuse_read_only(m.final_path, existing_path, "the results file");
  m.claim.emplace(m.final_path);
  m.lock.emplace(m.final_path);  // before the copy: it must hold every earlier update
  m.sweep_stale();
  m.tmp_path = temporary_for(m.final_path);
  m.tmp_handle = cleanup::remove_on_death(m.tmp_path);
  if (const std::string why = copy_whole_file(existing_path, m.tmp_path); !why.empty())
    throw InputError(existing_path.string() + ": cannot copy for update: " + why);
  m.open(false, "cannot open for update");
  return w;
}

ResultsWriter ResultsWriter::resume(const fs::path& final_path) {
  detail::quiet_hdf5();
  ResultsWriter w;
  w.impl_ = std::make_unique<Impl>();
  Impl& m = *w.impl_;
  m.final_path = link_target(final_path);
  refuse_read_only(m.final_path, final_path, "the results file");
  m.claim.emplace(m.final_path);
  m.make_folder();
  // A killed run's saved copy becomes FINAL.partial here.
  m.refuse_another_writer(m.sweep_stale());
  const fs::path partial = with_suffix(m.final_path, ".partial");
  m.tmp_path = temporary_for(m.final_path);
  m.tmp_handle = cleanup::remove_on_death(m.tmp_path);
  if (!fs::exists(partial)) {
    m.open(true, "cannot create results file");
    w.attr("/", "schema", kSchema);
    w.attr("/", "version", kVersion);
    w.attr("/", "git_sha", kGitSha);
    return w;
  }
  { ResultsReader check(partial); }  // refuses files that are not ours
  if (const std::string why = copy_whole_file(partial, m.tmp_path); !why.empty())
    throw InputError(partial.string() + ": cannot copy to resume: " + why);
  m.open(false, "cannot open to resume");
  return w;
}

ResultsWriter::ResultsWriter(ResultsWriter&&) noexcept = default;
ResultsWriter& ResultsWriter::operator=(ResultsWriter&&) noexcept = default;
ResultsWriter::~ResultsWriter() = default;

void ResultsWriter::attr(const std::string& object, const std::string& name, double value) {
  impl_->guarded(object, name, [&] {
    Handle space(H5Screate(H5S_SCALAR));
    impl_->write_attr(object, name, H5T_NATIVE_DOUBLE, space.get(), &value);
  });
  if (const char* unit = units::of_attribute(name)) attr(object, name + "_units", unit);
}
void ResultsWriter::attr(const std::string& object, const std::string& name, std::int64_t value) {
  impl_->guarded(object, name, [&] {
    Handle space(H5Screate(H5S_SCALAR));
    impl_->write_attr(object, name, H5T_NATIVE_INT64, space.get(), &value);
  });
}
void ResultsWriter::attr(const std::string& object, const std::string& name,
                         const std::string& value) {
  impl_->write_string_attr(object, name, value);
}
void ResultsWriter::attr(const std::string& object, const std::string& name, const char* value) {
  attr(object, name, std::string(value));
}
void ResultsWriter::attr(const std::string& object, const std::string& name,
                         const std::vector<double>& value) {
  impl_->guarded(object, name, [&] {
    const hsize_t n = value.size();
    Handle space(H5Screate_simple(1, &n, nullptr));
    impl_->write_attr(object, name, H5T_NATIVE_DOUBLE, space.get(), value.data());
  });
  if (const char* unit = units::of_attribute(name)) attr(object, name + "_units", unit);
}
void ResultsWriter::attr(const std::string& object, const std::string& name,
                         const std::vector<std::string>& value) {
  impl_->write_string_array_attr(object, name, value);
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

void ResultsWriter::remove(const std::string& path) {
  impl_->guarded(path, {}, [&] {
    if (link_exists(impl_->id(), path)) checked(H5Ldelete(impl_->id(), path.c_str(), H5P_DEFAULT));
  });
}

void ResultsWriter::create_group(const std::string& path) {
  impl_->guarded(path, {}, [&] { ensure_group(impl_->id(), path).close(); });
}

void ResultsWriter::commit() {
  Impl& m = *impl_;
  if (m.committed) throw std::logic_error("ResultsWriter::commit called twice");
  m.guarded("/", {}, [&] {
    checked(H5Fflush(m.id(), H5F_SCOPE_GLOBAL));
    Handle f = std::move(*m.file);
    m.file.reset();
    f.close();
  });
  std::error_code ec;
  {
    std::optional<FolderLock> rename_lock;
    if (!m.lock) rename_lock.emplace(m.final_path);
    keep_mode(m.final_path, m.tmp_path);
    fs::rename(m.tmp_path, m.final_path, ec);
  }
  if (ec)
    throw InputError(m.final_path.string() + ": cannot move results into place: " + ec.message());
  m.committed = true;
  m.lock.reset();
  cleanup::forget(m.tmp_handle);
  m.tmp_handle = -1;
  // The saved copy of the completed stages is superseded by the whole file.
  for (const fs::path& p : {m.partial_new, m.partial_copy})
    if (!p.empty()) fs::remove(p, ec);
  for (int h : {m.partial_handle, m.partial_new_handle}) cleanup::forget(h);
  m.claim.reset();  // nothing of this writer's is left in the folder
}

bool ResultsWriter::save_partial(const std::string& completed) {
  Impl& m = *impl_;
  if (m.committed || !m.file) return false;
  // The file on disk is now whole and consistent.
  if (H5Fflush(m.id(), H5F_SCOPE_GLOBAL) < 0) return false;
  if (m.partial_copy.empty()) {
    m.partial_copy = with_suffix(m.tmp_path, ".partial");
    m.partial_new = with_suffix(m.tmp_path, ".partial-new");
    m.partial_new_handle = cleanup::remove_on_death(m.partial_new);
  }
  const fs::path kept = with_suffix(m.final_path, ".partial");
  const std::string message =
      "rendulic: stopped by a signal; " + completed + " kept in " + kept.string();
  // The first copy is registered before it is renamed into place: registered after, a signal
  // in between left it behind as a temporary (it happened in CI). Before the rename the
  // entry finds no file and keeps nothing, as a signal before this save would. A later copy
  // replaces one that is registered: in that window the older entry keeps the new copy with
  // the older message, one stage short; the data are whole either way.
  const bool first = m.partial_handle < 0;
  const int early = first ? cleanup::rename_on_death(m.partial_copy, kept, message) : -1;
  std::error_code ec;
  if (!copy_whole_file(m.tmp_path, m.partial_new).empty())
    ec = std::make_error_code(std::errc::io_error);
  if (!ec) fs::rename(m.partial_new, m.partial_copy, ec);
  if (ec) {
    cleanup::forget(early);
    fs::remove(m.partial_new, ec);
    return false;
  }
  m.partial_completed = completed;
  if (first) {
    m.partial_handle = early;
  } else {
    cleanup::forget(m.partial_handle);
    m.partial_handle = cleanup::rename_on_death(m.partial_copy, kept, message);
  }
  return true;
}

std::string ResultsWriter::keep_partial() {
  Impl& m = *impl_;
  if (m.committed || m.partial_completed.empty()) return "";
  const fs::path kept = with_suffix(m.final_path, ".partial");
  std::error_code ec;
  fs::rename(m.partial_copy, kept, ec);
  if (ec) return "";
  cleanup::forget(m.partial_handle);
  m.partial_handle = -1;
  m.partial_copy.clear();
  return "; " + m.partial_completed + " kept in " + kept.string();
}

const std::vector<std::string>& ResultsWriter::notes() const { return impl_->notes; }
const fs::path& ResultsWriter::final_path() const { return impl_->final_path; }
const fs::path& ResultsWriter::temporary_path() const { return impl_->tmp_path; }

ResultsReader ResultsWriter::read_back() const {
  return ResultsReader(impl_->tmp_path, impl_->final_path);
}
fs::path ResultsWriter::partial_path() const { return with_suffix(impl_->final_path, ".partial"); }

// ========================================================================================
struct ResultsReader::Impl {
  fs::path path;
  std::unique_ptr<H5::H5File> holder;  // in place, see ResultsWriter::Impl

  [[noreturn]] void fail(const std::string& object, const std::string& why) const {
    throw InputError(path.string() + ": " + shown(object) + ": " + why);
  }

  // Runs `fn`, turning an HDF5 failure into one line naming the file and the object.
  template <class Fn>
  auto guarded(const std::string& object, Fn&& fn) const -> decltype(fn()) {
    detail::forget_hdf5_reason();
    try {
      return fn();
    } catch (const H5::Exception& e) {
      fail(object, "cannot be read (" + detail::hdf5_reason(e) + ")");
    } catch (const std::bad_alloc&) {
      fail(object, "holds more than this machine's memory can take");
    }
  }

  H5O_type_t require(const std::string& object) const {
    // An empty name is no object (it read "file: : is not a group").
    if (object.empty()) fail("''", "no such object (the root is '/')");
    if (object != "/" && !link_exists(holder->getId(), object)) fail(object, "missing");
    return object_type(holder->getId(), object);
  }
  H5::Group open_group(const std::string& object) const {
    if (require(object) != H5O_TYPE_GROUP) fail(object, "is not a group");
    return holder->openGroup(object);
  }
  H5::DataSet open_dataset(const std::string& object) const {
    if (require(object) != H5O_TYPE_DATASET) fail(object, "is not a dataset");
    return holder->openDataSet(object);
  }
  H5::Attribute open_attr(const std::string& object, const std::string& name) const {
    const H5O_type_t t = require(object);
    const std::string where = object + " @" + name;
    if (t == H5O_TYPE_DATASET) {
      H5::DataSet ds = holder->openDataSet(object);
      if (!ds.attrExists(name)) fail(where, "missing");
      return ds.openAttribute(name);
    }
    if (t != H5O_TYPE_GROUP) fail(object, "is neither a group nor a dataset");
    H5::Group g = holder->openGroup(object);
    if (!g.attrExists(name)) fail(where, "missing");
    return g.openAttribute(name);
  }
  // A numeric attribute of exactly `n` values (n = 0: any number of them).
  std::vector<double> numbers(const std::string& object, const std::string& name,
                              hssize_t n) const {
    const std::string where = object + " @" + name;
    return guarded(where, [&] {
      H5::Attribute a = open_attr(object, name);
      const auto cls = a.getTypeClass();
      if (cls != H5T_INTEGER && cls != H5T_FLOAT) fail(where, "is not a number");
      const hssize_t count = a.getSpace().getSimpleExtentNpoints();
      if (n > 0 && count != n)
        fail(where, "holds " + std::to_string(count) + " values, not " + std::to_string(n));
      std::vector<double> v(static_cast<std::size_t>(count));
      if (count) a.read(H5::PredType::NATIVE_DOUBLE, v.data());
      return v;
    });
  }
  // A dataset's doubles (converted by HDF5 from whatever numeric type it is stored as).
  std::vector<double> read_all(const std::string& p, std::vector<hsize_t>* dims) const {
    return guarded(p, [&] {
      H5::DataSet ds = open_dataset(p);
      const auto cls = ds.getTypeClass();
      if (cls != H5T_INTEGER && cls != H5T_FLOAT) fail(p, "does not hold numbers");
      H5::DataSpace space = ds.getSpace();
      if (!space.isSimple()) fail(p, "has no simple shape");
      std::vector<hsize_t> d(space.getSimpleExtentNdims());
      space.getSimpleExtentDims(d.data());
      hsize_t n = 1;
      for (auto x : d) {
        if (x != 0 && n > std::numeric_limits<hsize_t>::max() / x)
          fail(p, "declares more values than can be counted");
        n *= x;
      }
      expect_bytes_for(ds, p, n);
      std::vector<double> data(n);
      if (n) ds.read(data.data(), H5::PredType::NATIVE_DOUBLE);
      if (dims) *dims = d;
      return data;
    });
  }
  // A damaged or foreign file may declare more values than it holds (an extent grown over
  // chunks never written reads as fill values): refused before memory is asked for them. We
  // write every value, unfiltered; a compressed copy (h5repack) is allowed deflate's ratio
  // (at most about 1000:1) and then some.
  void expect_bytes_for(const H5::DataSet& ds, const std::string& p, hsize_t n) const {
    const hsize_t stored = ds.getStorageSize(), size = ds.getDataType().getSize();
    const bool filtered = ds.getCreatePlist().getNfilters() > 0;
    const long double needed = static_cast<long double>(n) * size;
    const long double room = filtered ? 4096.0L * stored + (1 << 20) : stored;
    if (needed > room)
      fail(p, "declares " + std::to_string(n) + " values but holds the bytes of " +
                  std::to_string(stored / std::max<hsize_t>(size, 1)) +
                  " (a damaged or unfinished file)");
  }
  void expect_shape(const std::string& p, const std::vector<hsize_t>& d,
                    std::initializer_list<long> tail) const {
    bool ok = d.size() == tail.size() + 1;
    std::size_t i = 1;
    for (long t : tail) ok = ok && i < d.size() && d[i++] == static_cast<hsize_t>(t);
    if (!ok) fail(p, "has an unexpected shape");
  }
};

ResultsReader::ResultsReader(const fs::path& path) : ResultsReader(path, path) {}

ResultsReader::ResultsReader(const fs::path& path, const fs::path& shown_as)
    : impl_(std::make_unique<Impl>()) {
  detail::quiet_hdf5();
  impl_->path = shown_as;
  refuse_unless_regular_file(path, shown_as.string(), "results file", "an HDF5 file");
  {
    // Open it ourselves first: HDF5 reports an unreadable file as "not HDF5".
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) throw InputError(shown_as.string() + ": cannot read: " + std::strerror(errno));
    ::close(fd);
  }
  bool is_h5 = false;
  try {
    is_h5 = H5::H5File::isHdf5(path.string());
  } catch (const H5::Exception&) {
    is_h5 = false;
  }
  if (!is_h5) throw InputError(shown_as.string() + ": not an HDF5 file");
  detail::forget_hdf5_reason();
  try {
    impl_->holder = std::make_unique<H5::H5File>(path.string(), H5F_ACC_RDONLY);
  } catch (const H5::Exception& e) {
    // HDF5 locks a file it writes: a reader then fails with EAGAIN, which is no corruption (a
    // notebook holding the file in h5py's "r+" or "a" mode, a run's temporary file).
    if (locked_by_a_writer(path))
      throw InputError(shown_as.string() +
                       ": another program has it open for writing (HDF5's file lock); close it "
                       "there, or wait for it to finish");
    const std::string why = detail::hdf5_reason(e);
    throw InputError(shown_as.string() +
                     (detail::hdf5_refused_locks() ? ": cannot open: "
                                                   : ": cannot open (corrupt HDF5 file?): ") +
                     why);
  }
  std::string schema;
  try {
    schema = attr_string("/", "schema");
  } catch (const InputError&) {
    // An integer @schema was reported as "no schema attribute".
    throw InputError(
        shown_as.string() + ": not a rendulic results file (" +
        (has_attr("/", "schema") ? "its schema attribute is not one text" : "no schema attribute") +
        ")");
  }
  if (schema != kSchema && schema != kSchemaPrevious)
    throw InputError(shown_as.string() + ": schema '" + shown(schema) + "' is not " + kSchema +
                     " (or the previous " + kSchemaPrevious + "); a newer rendulic wrote it?");
}

ResultsReader::ResultsReader(ResultsReader&&) noexcept = default;
ResultsReader::~ResultsReader() = default;

bool ResultsReader::exists(const std::string& path) const {
  return path == "/" ||
         impl_->guarded(path, [&] { return link_exists(impl_->holder->getId(), path); });
}

bool ResultsReader::is_group(const std::string& path) const {
  return exists(path) && object_type(impl_->holder->getId(), path) == H5O_TYPE_GROUP;
}

bool ResultsReader::has_attr(const std::string& object, const std::string& name) const {
  if (!exists(object)) return false;
  return impl_->guarded(object, [&] {
    const H5O_type_t t = object_type(impl_->holder->getId(), object);
    if (t == H5O_TYPE_DATASET) return impl_->holder->openDataSet(object).attrExists(name);
    if (t == H5O_TYPE_GROUP) return impl_->holder->openGroup(object).attrExists(name);
    return false;
  });
}

std::vector<std::string> ResultsReader::children(const std::string& group) const {
  if (!exists(group)) return {};
  return impl_->guarded(group, [&] {
    std::vector<std::string> out;
    H5::Group g = impl_->open_group(group);
    for (hsize_t i = 0; i < g.getNumObjs(); ++i) out.push_back(g.getObjnameByIdx(i));
    return out;
  });
}

std::vector<std::string> pressure_branches(const ResultsReader& in) {
  std::vector<std::string> out;
  if (!in.is_group(paths::kPressure)) return out;
  for (const std::string& c : in.children(paths::kPressure))
    out.push_back(std::string(paths::kPressure) + "/" + c);
  return out;
}

std::vector<std::string> state_roots(const ResultsReader& in) {
  std::vector<std::string> out = {""};
  for (std::string& b : pressure_branches(in)) out.push_back(std::move(b));
  return out;
}

std::vector<std::string> ResultsReader::attr_names(const std::string& object) const {
  return impl_->guarded(object, [&] {
    std::vector<std::string> out;
    const auto collect = [&](const H5::H5Object& o) {
      for (int i = 0; i < o.getNumAttrs(); ++i)
        out.push_back(o.openAttribute(static_cast<unsigned>(i)).getName());
    };
    if (impl_->require(object) == H5O_TYPE_DATASET)
      collect(impl_->holder->openDataSet(object));
    else
      collect(impl_->open_group(object));
    return out;
  });
}

bool ResultsReader::attr_is_text(const std::string& object, const std::string& name) const {
  return impl_->guarded(object + " @" + name, [&] {
    return impl_->open_attr(object, name).getTypeClass() == H5T_STRING;
  });
}

double ResultsReader::attr_double(const std::string& object, const std::string& name) const {
  return impl_->numbers(object, name, 1)[0];
}
std::int64_t ResultsReader::attr_int(const std::string& object, const std::string& name) const {
  const std::string where = object + " @" + name;
  return impl_->guarded(where, [&]() -> std::int64_t {
    H5::Attribute a = impl_->open_attr(object, name);
    const auto cls = a.getTypeClass();
    if (cls != H5T_INTEGER && cls != H5T_FLOAT) impl_->fail(where, "is not a number");
    if (a.getSpace().getSimpleExtentNpoints() != 1) impl_->fail(where, "is not one number");
    if (cls == H5T_INTEGER) {  // read as int64: a seed above 2^53 must not pass through double
      std::int64_t i = 0;
      a.read(H5::PredType::NATIVE_INT64, &i);
      return i;
    }
    double v = 0;
    a.read(H5::PredType::NATIVE_DOUBLE, &v);
    if (!(v == std::floor(v)) || !(std::abs(v) < 9.2e18)) impl_->fail(where, "is not an integer");
    return static_cast<std::int64_t>(v);
  });
}
std::string ResultsReader::attr_string(const std::string& object, const std::string& name) const {
  const std::string where = object + " @" + name;
  return impl_->guarded(where, [&] {
    H5::Attribute a = impl_->open_attr(object, name);
    if (a.getTypeClass() != H5T_STRING) impl_->fail(where, "is not text");
    if (a.getSpace().getSimpleExtentNpoints() != 1) impl_->fail(where, "is not one text");
    std::string v;
    a.read(a.getStrType(), v);
    return v;
  });
}
std::vector<std::string> ResultsReader::attr_strings(const std::string& object,
                                                     const std::string& name,
                                                     char separator) const {
  const std::string where = object + " @" + name;
  return impl_->guarded(where, [&] {
    H5::Attribute a = impl_->open_attr(object, name);
    if (a.getTypeClass() != H5T_STRING) impl_->fail(where, "is not text");
    const hssize_t n = a.getSpace().getSimpleExtentNpoints();
    std::vector<std::string> out;
    if (a.getSpace().getSimpleExtentNdims() == 0) {
      // Schema rendulic/1 joined a list into one text.
      std::string joined;
      a.read(a.getStrType(), joined);
      std::stringstream ss(joined);
      for (std::string item; std::getline(ss, item, separator);)
        if (!item.empty()) out.push_back(item);
      return out;
    }
    if (!a.getStrType().isVariableStr()) impl_->fail(where, "is not a list of variable texts");
    if (n == 0) return out;
    std::vector<char*> texts(static_cast<std::size_t>(n), nullptr);
    a.read(a.getStrType(), texts.data());
    for (char* t : texts) out.emplace_back(t ? t : "");
    H5Dvlen_reclaim(a.getStrType().getId(), a.getSpace().getId(), H5P_DEFAULT, texts.data());
    return out;
  });
}
std::vector<double> ResultsReader::attr_doubles(const std::string& object,
                                                const std::string& name) const {
  return impl_->numbers(object, name, 0);
}

std::vector<std::uint64_t> ResultsReader::shape(const std::string& path) const {
  return impl_->guarded(path, [&] {
    H5::DataSpace space = impl_->open_dataset(path).getSpace();
    std::vector<hsize_t> d(space.getSimpleExtentNdims());
    space.getSimpleExtentDims(d.data());
    return std::vector<std::uint64_t>(d.begin(), d.end());
  });
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
  if (m.rows() != 3 || m.cols() != 3) impl_->fail(path, "is not 3x3");
  return m;
}
Eigen::MatrixXd ResultsReader::read_matrix(const std::string& path) const {
  std::vector<hsize_t> d;
  auto data = impl_->read_all(path, &d);
  if (d.size() != 2) impl_->fail(path, "is not a matrix");
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
  if (cls == H5T_STRING && n == 1) {
    std::string s;
    a.read(a.getStrType(), s);
    const auto nl = s.find('\n');
    if (nl != std::string::npos || s.size() > 60)
      out << '"' << shown(s.substr(0, std::min<std::size_t>(nl, 60))) << "...\" (" << s.size()
          << " chars)";
    else
      out << '"' << shown(s) << '"';
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

// Address of an object in the file: two hard links to one group share it.
haddr_t address_of(const H5::H5Object& obj) {
  H5O_info_t info;
  return H5Oget_info(obj.getId(), &info) < 0 ? HADDR_UNDEF : info.addr;
}

struct Describer {
  const H5::H5File& f;
  std::ostringstream& out;
  std::map<haddr_t, std::string> seen;  // group address -> first path it was reached by

  void attrs(H5::H5Object& obj, const std::string& indent) {
    for (int i = 0; i < obj.getNumAttrs(); ++i) {
      H5::Attribute a = obj.openAttribute(static_cast<unsigned>(i));
      out << indent << "  @" << shown(a.getName()) << " = " << attr_text(a) << "\n";
    }
  }
  void group(const std::string& path, int depth) {
    const std::string indent(2 * depth, ' ');
    H5::Group g = f.openGroup(path);
    const std::string label = path == "/" ? "/" : shown(split_path(path).back()) + "/";
    const auto [it, fresh] = seen.emplace(address_of(g), path);
    if (!fresh) {  // a hard link back to a group already shown: a cycle or an alias
      out << indent << label << " -> same group as " << shown(it->second) << "\n";
      return;
    }
    out << indent << label << "\n";
    attrs(g, indent);
    for (hsize_t i = 0; i < g.getNumObjs(); ++i) {
      const std::string name = g.getObjnameByIdx(i);
      const std::string child = (path == "/" ? "" : path) + "/" + name;
      if (!link_exists(f.getId(), child)) {
        out << indent << "  " << shown(name) << " (dangling link)\n";
        continue;
      }
      const H5O_type_t type = object_type(f.getId(), child);
      if (type == H5O_TYPE_GROUP) {
        group(child, depth + 1);
      } else if (type == H5O_TYPE_DATASET) {
        H5::DataSet ds = f.openDataSet(child);
        H5::DataSpace space = ds.getSpace();
        std::vector<hsize_t> d(std::max(0, space.getSimpleExtentNdims()));
        space.getSimpleExtentDims(d.data());
        out << indent << "  " << shown(name) << " [";
        for (std::size_t k = 0; k < d.size(); ++k) out << (k ? "," : "") << d[k];
        out << "]" << (ds.getTypeClass() == H5T_STRING ? " text" : "") << "\n";
        attrs(ds, indent);
      } else {
        out << indent << "  " << shown(name) << " (not a group or dataset)\n";
      }
    }
  }
};
}  // namespace

std::string ResultsReader::summary() const {
  std::ostringstream out;
  out << impl_->path.string() << " (" << kSchema << ")\n";
  impl_->guarded("/", [&] {
    Describer d{*impl_->holder, out, {}};
    d.group("/", 0);
  });
  return out.str();
}

}  // namespace rendulic
