// Packings in the files of other DEM engines and of rendulic's own results (docs/interop.md):
// spheres in an orthorhombic periodic box, read from a LAMMPS data file (atom_style sphere), a
// LAMMPS text dump (id, radius or diameter, positions) or a state of a results file, and
// written as a LAMMPS data file. Pure file I/O on a plain value: the DEM engine turns a Packing
// into a system (app/packing_system.hpp), and never reads files itself.
//
// Every defect of a file (a missing column, another atom style, a triclinic or degenerate box,
// a non-finite number, a duplicate atom id, a count that does not match) is an InputError of
// one line naming the file and, where there is one, its line.
#pragma once

#include <Eigen/Dense>
#include <filesystem>
#include <string>
#include <vector>

namespace rendulic {

struct Packing {
  Eigen::MatrixXd positions;         // [N,3], m, wrapped into [0, L_a) on each axis
  std::vector<double> radii;         // m, > 0
  Eigen::MatrixXd velocities;        // [N,3], m/s; 0 rows when the file holds none
  Eigen::Vector3d lengths{1, 1, 1};  // the periodic box, m
  std::vector<double> densities;     // kg/m^3 per particle (a LAMMPS data file); else empty
  std::string origin;                // what was read: "FILE (LAMMPS data file)", for messages
  std::string units;  // the unit style the file declares (a dump's ITEM: UNITS, write_data's
                      // title "..., units = si"), else empty

  std::size_t size() const { return radii.size(); }
  double mean_radius() const;
  double volume_fraction() const;  // sum of sphere volumes over the box volume
};

// The three kinds of packing file. A PACKING argument "FILE:OBJECT" whose FILE is a file names a
// state of a results file (OBJECT a group such as /states/a, or a bare label a for /states/a);
// otherwise the file's first line tells a dump ("ITEM: TIMESTEP") from a data file.
enum class PackingFormat { kLammpsData, kLammpsDump, kResultsState };
struct PackingSource {
  std::filesystem::path file;
  std::string object;  // the state's group (kResultsState), else empty
  PackingFormat format = PackingFormat::kLammpsData;
};
PackingSource packing_source(const std::string& argument);
// The label a state group ends with (/states/a -> a), or `fallback` for the other formats.
std::string packing_label(const PackingSource& source, const std::string& fallback);

Packing read_packing(const PackingSource& source);
// LAMMPS `write_data` layout: header (N atoms, the box), then the sections Atoms (# sphere: id
// type diameter density x y z [ix iy iz]) and optionally Velocities (id vx vy vz [wx wy wz]);
// other sections (Masses, Pair Coeffs, ...) are skipped. The unit style write_data names in the
// title is kept in `units`.
Packing read_lammps_data(const std::filesystem::path& file);
// LAMMPS `dump custom` text: the last snapshot of the file; columns id, radius or diameter, and
// x y z, xu yu zu (unwrapped) or xs ys zs (scaled); vx vy vz when present. Periodic boundaries
// (pp) on every axis. The items of `dump_modify units yes` and `time yes` are read past (the
// unit style is kept in `units`; the numbers are taken as SI whatever it says).
Packing read_lammps_dump(const std::filesystem::path& file);
// A state of a results file (docs/results.md /states/<label>): positions, radii, cell lengths,
// and the velocities of its checkpoint when it has one.
Packing read_results_state(const std::filesystem::path& file, const std::string& group);

// The packing as a LAMMPS data file (atom_style sphere, box [0, L_a), one atom type, the given
// density for every atom, and a Velocities section: the packing's, or zero), numbers with 17
// significant digits so that reading it back gives the same doubles. `title` is the first line.
// Written whole or not at all (AtomicTextFile): a failed write leaves an earlier FILE as it was.
void write_lammps_data(const std::filesystem::path& file, const Packing& packing, double density,
                       const std::string& title);

}  // namespace rendulic
