// Text files in and out. In: a user's input file read whole, refused in one line when it is not
// one (read_input_text). Out: a text output written whole or not at all (docs/usage.md "Results
// are atomic"): the text goes
// to a temporary file beside the final one (.NAME.tmp-PID), which commit() renames onto it. A
// full disk, a file-size limit or a signal leaves the earlier file as it was and no half-written
// one; the temporary is removed on failure and on death by a signal (core/cleanup.hpp). Used by
// every text file the commands write: calibrate --out, report.md, the sweep's CSVs, exported
// LAMMPS data files and bench's pair lines. A symbolic link is written through (its target
// replaced, the link kept); a device, FIFO or socket (/dev/stdout, /dev/null) is written to as
// it is, once, at commit().
#pragma once

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace rendulic {

// The text of a user's input file (a scenario, law parameters, a material state, an envelope
// CSV), read whole. Opened without blocking and checked on the open descriptor: a FIFO must not
// hang the command, a folder or a device (/dev/zero) is not such a file, and one larger than
// `max_bytes` (a whole number of MiB) is refused before it is read. Each refusal is an
// InputError naming the file and `what` ("scenario file"): "PATH: cannot read WHAT: REASON",
// "PATH: is a folder, not a WHAT", "PATH: not a regular file (a WHAT is a text file)", "PATH:
// larger than N MiB, not a WHAT".
std::string read_input_text(const std::string& path, const std::string& what,
                            std::size_t max_bytes);

// The refusal of an input that is not a regular file, in the words every command uses (a
// results file, a packing, a UMAT library and read_input_text's text files): "SHOWN: no such
// file", "SHOWN: cannot read WHAT: REASON", "SHOWN: is a folder, not a WHAT" and "SHOWN: not a
// regular file (a WHAT is FORM)" for a device, FIFO or socket; FORM says what the file should
// be ("a text file", "an HDF5 file"). Checked with stat, which does not block on a FIFO;
// returns quietly for a regular file (or a link to one).
void refuse_unless_regular_file(const std::filesystem::path& path, const std::string& shown,
                                const std::string& what, const std::string& form);
// The same refusal for a file type already known (st_mode of an open descriptor).
void refuse_unless_regular_mode(unsigned mode, const std::string& shown, const std::string& what,
                                const std::string& form);

// Makes the folder `dir` and any missing folders above it (nothing for an empty `dir`, the
// current folder) and returns those it made, innermost first, for a caller that removes them
// again if they stay empty. A file where a folder must be is named: "F: is a file, not a folder
// (the WHAT)", or "(it cannot hold the WHAT DIR)" for a file above it, where the system said
// "Not a directory"; any other failure is "DIR: cannot create the WHAT: REASON", and the
// folders made on the way are removed again.
std::vector<std::filesystem::path> make_folders(const std::filesystem::path& dir,
                                                const std::string& what);
// make_folders' refusal of a file where `dir` or a folder above it must be, alone and in the
// same words, for a check before any work; it makes nothing.
void refuse_file_in_place_of_folder(const std::filesystem::path& dir, const std::string& what);

// The file a name stands for: a symbolic link followed to its target (which may not exist yet),
// at most 40 deep as the kernel does; any other name as it is. Writers that replace a file by
// renaming onto it replace the target, so that the link stays.
std::filesystem::path link_target(std::filesystem::path p);

// Two rules of every writer that replaces a file by renaming a temporary onto it (this class
// and ResultsWriter, docs/usage.md "Results are atomic"), since a rename needs only the
// folder's permission and makes the file the temporary's:
// - a `target` that exists and that this process may not write (access(W_OK): a user's
//   chmod a-w; root may write any) is refused before any work, InputError "SHOWN: cannot write
//   WHAT: reason" (a protected results file was replaced without a word);
void refuse_read_only(const std::filesystem::path& target, const std::filesystem::path& shown,
                      const std::string& what);
// - the `replacement` gets the permissions of `existing` (and its owner and group where this
//   process may give them) just before the rename: a results file of mode 600 became 644,
//   readable by all, after `rendulic fit --results`. A new file gets 666 less the umask, as
//   every other program's.
void keep_mode(const std::filesystem::path& existing, const std::filesystem::path& replacement);

class AtomicTextFile {
 public:
  // Creates the temporary now, so that a place that cannot be written is refused (InputError,
  // "FILE: cannot write WHAT: reason") before any work is done. `what` names the file in
  // messages ("the JSON output"). A FILE that is a folder is refused too.
  AtomicTextFile(std::filesystem::path file, std::string what);
  // The constructor's refusal of a FILE that is a folder, for a command that checks its
  // destinations before long work that ends in writing them (a run's report.md).
  static void refuse_folder(const std::filesystem::path& file, const std::string& what);
  AtomicTextFile(const AtomicTextFile&) = delete;
  AtomicTextFile& operator=(const AtomicTextFile&) = delete;
  // Without commit(), removes the temporary.
  ~AtomicTextFile();

  // The text, kept in memory until flush() or commit().
  std::ostream& stream() {
    flushed_ = false;
    return text_;
  }
  // Writes the text to the temporary and checks that every byte reached the disk; InputError
  // naming the file and the reason otherwise (the temporary then gone). For a caller that must
  // know the file fits before it replaces another (calibrate writes its JSON before it replaces
  // results.h5, and renames it after).
  void flush();
  // flush() unless done since the last change, then renames the temporary onto the final name.
  void commit();
  const std::filesystem::path& path() const { return final_; }

 private:
  // Writes the text into `file` (opened with O_WRONLY | flags), fsynced if `sync`.
  void write_to(const std::filesystem::path& file, int flags, bool sync);

  // The name given, and the file it stands for (a symbolic link followed).
  std::filesystem::path final_, target_, tmp_;
  std::string what_;
  std::ostringstream text_;
  int handle_ = -1;
  // A device, FIFO or socket: written as it is, without a temporary.
  bool direct_ = false;
  bool flushed_ = false, done_ = false;
};

}  // namespace rendulic
