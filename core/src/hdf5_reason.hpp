// One-line reasons for HDF5 failures, shared by results.cpp and errors.cpp (not installed).
// HDF5 1.10's C++ exceptions are not std::exception and carry only the outermost function's
// name ("H5Dwrite failed"); the useful reason (a full disk, a missing object) is deeper in
// HDF5's error stack, which is still intact inside the catch block.
#pragma once

#include <H5Cpp.h>

#include <string>

namespace rendulic::detail {

// Replaces HDF5's automatic printing of its error stack (once per process) by a recorder of
// the failing call's reason: every failure must become one line of ours.
void quiet_hdf5();

// Forgets the recorded reason; called before an operation whose failure will be reported.
void forget_hdf5_reason();

// The reason recorded for the last failed call: the system's error text if HDF5's stack
// holds one ("No space left on device"), else the innermost description ("object 'x'
// doesn't exist"), else "HDF5 error" (or the exception's own message).
std::string hdf5_reason();
std::string hdf5_reason(const H5::Exception& e);
// The last failed call failed because the file system refuses file locks (the reason then says
// so and names HDF5_USE_FILE_LOCKING=FALSE): no sign of a damaged file.
bool hdf5_refused_locks();

}  // namespace rendulic::detail
