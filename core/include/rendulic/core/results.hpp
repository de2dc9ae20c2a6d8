// Results files (HDF5 C++ API), schema "rendulic/2" of docs/results.md (rendulic/1 still read). The
// writer builds the file under a temporary name in the output folder and renames it onto the
// final name only in commit(): a run that fails or is interrupted leaves no file that looks
// complete, and a results file from an earlier run stays untouched until the new one is
// whole. A run may save a consistent copy of what its completed stages wrote (save_partial);
// on failure that copy becomes FINAL.partial (docs/usage.md "Results are atomic"). Groups
// along a dataset path are created on demand. Every HDF5 failure, of the writer (a full
// disk) or of the reader (a file that is not ours, damaged, or of the wrong shape or type),
// is an InputError of one line naming the file and the object, never an HDF5 exception.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace rendulic {

class ResultsReader;

class ResultsWriter {
 public:
  // A new file that will become `final_path` on commit(); creates the folder if needed and
  // stamps the root attributes schema, version and git_sha.
  explicit ResultsWriter(const std::filesystem::path& final_path);
  // Modifies an existing results file atomically: works on a temporary copy, renamed back
  // over the original on commit().
  static ResultsWriter update(const std::filesystem::path& existing_path);
  // Continues an interrupted run (docs/usage.md "Resuming a run"): starts from a copy of the
  // stages it kept in FINAL.partial (after taking over a killed run's saved copy, as the
  // constructor does), or from a new file like the constructor when there is none. The partial
  // file is left alone: the caller removes it once commit() succeeded.
  static ResultsWriter resume(const std::filesystem::path& final_path);
  ResultsWriter(ResultsWriter&&) noexcept;
  ResultsWriter& operator=(ResultsWriter&&) noexcept;
  // Without commit(), removes the temporary file: nothing half-written survives.
  ~ResultsWriter();

  // Attributes on a group (created if absent) or an existing dataset.
  void attr(const std::string& object, const std::string& name, double value);
  void attr(const std::string& object, const std::string& name, std::int64_t value);
  void attr(const std::string& object, const std::string& name, const std::string& value);
  void attr(const std::string& object, const std::string& name, const char* value);
  void attr(const std::string& object, const std::string& name, const std::vector<double>& value);
  // A list of texts: an HDF5 array of variable-length strings.
  void attr(const std::string& object, const std::string& name,
            const std::vector<std::string>& value);

  // Fixed datasets, replacing any dataset of the same path: [n], [n,2], [n,3,3], [3,3], [r,c].
  void write(const std::string& path, const std::vector<double>& values);
  void write(const std::string& path, const std::vector<Eigen::Vector2d>& pairs);
  void write(const std::string& path, const std::vector<Eigen::Matrix3d>& tensors);
  void write(const std::string& path, const Eigen::Matrix3d& tensor);
  void write(const std::string& path, const Eigen::MatrixXd& matrix);

  // Growable series: each call adds one row to [n], [n,2] or [n,3,3] (chunked, unlimited).
  void append(const std::string& path, double value);
  void append(const std::string& path, const Eigen::Vector2d& pair);
  void append(const std::string& path, const Eigen::Matrix3d& tensor);

  void create_group(const std::string& path);
  // Removes the object at `path` (a group with all it holds), if there is one: a group written
  // again from scratch keeps none of its earlier attributes.
  void remove(const std::string& path);
  // Flushes, closes, renames the temporary file onto the final path. Once only.
  void commit();

  // Saves a consistent copy of everything written so far (flush, then copy beside the
  // temporary file), replacing the previous copy; `completed` says what it holds (e.g. "the
  // stages prepare, isotropic"). If the process is then stopped by a signal, the copy is
  // renamed to FINAL.partial and a line saying so goes to stderr. Returns false (keeping the
  // previous copy) if the copy cannot be made, e.g. on a full disk.
  bool save_partial(const std::string& completed);
  // After a failure, before the writer is destroyed: moves the last saved copy onto
  // FINAL.partial (never onto FINAL) and returns a note for the error line ("; the stages
  // prepare, isotropic are kept in out/results.h5.partial"), or "" if nothing was saved.
  std::string keep_partial();

  // Lines about stale temporary files of killed runs that the constructor found in the
  // output folder and removed (or kept as FINAL.partial); for the caller to print.
  const std::vector<std::string>& notes() const;

  const std::filesystem::path& final_path() const;
  const std::filesystem::path& temporary_path() const;
  // A reader of what has been written so far, named as the final file in its messages and in
  // what it stores (a fit's `error`): the temporary's name is gone once the writer commits.
  ResultsReader read_back() const;
  // FINAL.partial: where a failed run keeps its completed stages, and resume() starts from.
  std::filesystem::path partial_path() const;

 private:
  ResultsWriter() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class ResultsReader {
 public:
  // InputError naming the file if it is missing, unreadable, not HDF5, corrupt, or lacks
  // schema rendulic/2 or rendulic/1. Every accessor below throws an InputError naming the file and
  // the object when it is missing, of the wrong kind (a group for a dataset), type (text for
  // numbers) or shape, or cannot be read.
  explicit ResultsReader(const std::filesystem::path& path);
  // Reads `path` but names `shown_as` in every message and in path(): e.g. a working copy of
  // DIR/results.h5.partial, named as the file the user knows.
  ResultsReader(const std::filesystem::path& path, const std::filesystem::path& shown_as);
  ResultsReader(ResultsReader&&) noexcept;
  ~ResultsReader();

  // True if `path` names an object that can be opened (a dangling link does not exist).
  bool exists(const std::string& path) const;
  bool is_group(const std::string& path) const;
  bool has_attr(const std::string& object, const std::string& name) const;
  std::vector<std::string> children(const std::string& group) const;
  // The names of the attributes of a group or dataset, and whether one of them is text (else
  // numbers): what a reader that does not know the names beforehand needs (the Python module's
  // dictionaries of attributes).
  std::vector<std::string> attr_names(const std::string& object) const;
  bool attr_is_text(const std::string& object, const std::string& name) const;

  double attr_double(const std::string& object, const std::string& name) const;
  std::int64_t attr_int(const std::string& object, const std::string& name) const;
  std::string attr_string(const std::string& object, const std::string& name) const;
  std::vector<double> attr_doubles(const std::string& object, const std::string& name) const;
  // A list of texts: an array of strings, or (schema rendulic/1) one text joined with
  // `separator`.
  std::vector<std::string> attr_strings(const std::string& object, const std::string& name,
                                        char separator = ',') const;

  std::vector<std::uint64_t> shape(const std::string& path) const;
  std::vector<double> read_vector(const std::string& path) const;
  std::vector<Eigen::Vector2d> read_pairs(const std::string& path) const;
  std::vector<Eigen::Matrix3d> read_tensors(const std::string& path) const;
  Eigen::Matrix3d read_tensor(const std::string& path) const;
  Eigen::MatrixXd read_matrix(const std::string& path) const;

  // Human summary for `rendulic inspect`: every group, its attributes, dataset shapes; a
  // group reached a second time (a hard-link cycle) is named, not descended into again.
  std::string summary() const;
  const std::filesystem::path& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The pressure branches of a results file, /pressure/nu<nu> (docs/results.md), in file order;
// none if it has no /pressure group.
std::vector<std::string> pressure_branches(const ResultsReader& in);
// The roots that may hold a /states group: "" (the run's own states) and each pressure branch.
// Whatever walks every state (fitting, the report, a wrong label's list) walks these.
std::vector<std::string> state_roots(const ResultsReader& in);

}  // namespace rendulic
