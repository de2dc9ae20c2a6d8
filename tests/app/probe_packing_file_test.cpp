// The packing readers and writer (core/packing_file.hpp, docs/interop.md) on small files whose
// packing is known by construction: a box not at the origin, atoms out of order, positions
// outside the box and image flags, sections to skip, velocities matched by id; a dump with two
// snapshots in scaled, unwrapped and plain coordinates; and the writer read back bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/packing_file.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::Packing;

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "app_packing_file";
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

TEST(PackingFile, DataFileIsReadRelativeToItsBoxOrderedByIdAndWrapped) {
  const fs::path f = write("shifted.data",
                           "LAMMPS data file via write_data\n\n3 atoms\n1 atom types\n\n"
                           "-1 1 xlo xhi\n2 4 ylo yhi\n0 3 zlo zhi\n0 0 0 xy xz yz\n\n"
                           "Masses\n\n1 1.0\n\n"
                           "Atoms # sphere\n\n"
                           "3 1 0.2 2000 0.5 2.5 2.5 0 0 0\n"
                           "1 1 0.4 1000 -0.5 3.0 0.25 1 0 0\n"
                           "2 1 0.6 2000 1.25 1.5 3.5 0 0 -1\n\n"
                           "Velocities\n\n2 0.2 0.0 0.0 0 0 0\n1 0.1 0.0 0.0 0 0 0\n"
                           "3 0.3 0.0 0.0 0 0 0\n");
  const rendulic::PackingSource src = rendulic::packing_source(f.string());
  EXPECT_EQ(src.format, rendulic::PackingFormat::kLammpsData);
  const Packing p = rendulic::read_packing(src);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p.lengths, Eigen::Vector3d(2, 2, 3));
  EXPECT_EQ(p.radii, (std::vector<double>{0.2, 0.3, 0.1}));
  EXPECT_EQ(p.densities, (std::vector<double>{1000, 2000, 2000}));
  // Relative to (xlo, ylo, zlo) = (-1, 2, 0), wrapped into [0, L): image flags do not matter.
  EXPECT_EQ(p.positions.row(0), Eigen::RowVector3d(0.5, 1.0, 0.25));
  EXPECT_EQ(p.positions.row(1), Eigen::RowVector3d(0.25, 1.5, 0.5));  // y 1.5 - 2 + 2, z 3.5 - 3
  EXPECT_EQ(p.positions.row(2), Eigen::RowVector3d(1.5, 0.5, 2.5));
  EXPECT_EQ(p.velocities.col(0), Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_NEAR(p.mean_radius(), 0.2, 1e-15);
}

// LAMMPS's write_data names the unit style in the title since 2022 (Debian 12's of 2021 does
// not): it is kept for probe's warning about units other than si; another title says nothing.
TEST(PackingFile, DataFileTitleFromWriteDataGivesItsUnits) {
  const std::string body =
      "\n1 atoms\n1 atom types\n\n0 2 xlo xhi\n0 2 ylo yhi\n0 2 zlo zhi\n\n"
      "Atoms # sphere\n\n1 1 0.4 2000 1 1 1\n";
  const struct {
    const char* title;
    const char* units;
  } cases[] = {
      {"LAMMPS data file via write_data, version 2 Aug 2023, timestep = 0, units = cgs", "cgs"},
      {"LAMMPS data file via write_data, version 29 Sep 2021, timestep = 0", ""},
      {"my packing, units = lj", ""},
  };
  for (const auto& c : cases)
    EXPECT_EQ(rendulic::read_lammps_data(write("title.data", c.title + ("\n" + body))).units,
              c.units)
        << c.title;
}

// Another engine may write a velocity that underflowed (a subnormal, strtod's ERANGE): it is a
// number, read as it is; it used to be refused as "not a finite number".
TEST(PackingFile, ASubnormalNumberIsReadAsItIs) {
  const fs::path f = write("subnormal.data",
                           "LAMMPS data file\n\n1 atoms\n1 atom types\n\n"
                           "0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n\n"
                           "Atoms # sphere\n\n1 1 0.2 2000 0.5 0.5 0.5 0 0 0\n\n"
                           "Velocities\n\n1 1e-320 -4.9e-324 1e-400 0 0 0\n");
  const Packing p = rendulic::read_packing(rendulic::packing_source(f.string()));
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p.velocities(0, 0), 1e-320);
  EXPECT_EQ(p.velocities(0, 1), -4.9e-324);
  EXPECT_EQ(p.velocities(0, 2), 0.0);
  const fs::path bad = write("hex.data",
                             "LAMMPS data file\n\n1 atoms\n1 atom types\n\n"
                             "0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n\n"
                             "Atoms # sphere\n\n1 1 0x1p-2 2000 0.5 0.5 0.5 0 0 0\n");
  try {
    rendulic::read_packing(rendulic::packing_source(bad.string()));
    ADD_FAILURE() << "a hexadecimal diameter was read";
  } catch (const rendulic::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'0x1p-2' is not a finite decimal number"),
              std::string::npos)
        << e.what();
  }
}

TEST(PackingFile, DumpGivesItsLastSnapshotInAnyCoordinateColumns) {
  const std::string head =
      "ITEM: TIMESTEP\n{T}\nITEM: NUMBER OF ATOMS\n2\n"
      "ITEM: BOX BOUNDS pp pp pp\n1 3\n0 2\n0 4\n";
  auto snapshot = [&](const std::string& t, const std::string& cols, const std::string& rows) {
    std::string h = head;
    h.replace(h.find("{T}"), 3, t);
    return h + "ITEM: ATOMS " + cols + "\n" + rows;
  };
  // Scaled, then unwrapped, then plain coordinates of the same two spheres.
  const std::string scaled = snapshot("0", "id type xs ys zs radius vx vy vz",
                                      "2 1 0.25 0.75 0.5 0.1 0 0 1\n1 1 0.5 0.5 0.125 0.2 1 0 0\n");
  const std::string unwrapped =
      snapshot("10", "id diameter xu yu zu", "1 0.4 4 3 -3.5\n2 0.2 1.5 -0.5 2\n");
  const std::string plain = snapshot("20", "diameter x y z id", "0.4 2 1 0.5 1\n0.2 1.5 1.5 2 2\n");
  for (const std::string& text : {scaled, plain + unwrapped, scaled + plain}) {
    const fs::path f = write("two.dump", text);
    EXPECT_EQ(rendulic::packing_source(f.string()).format, rendulic::PackingFormat::kLammpsDump);
    const Packing p = rendulic::read_lammps_dump(f);
    ASSERT_EQ(p.size(), 2u);
    EXPECT_EQ(p.lengths, Eigen::Vector3d(2, 2, 4));
    EXPECT_EQ(p.radii, (std::vector<double>{0.2, 0.1}));
    EXPECT_EQ(p.positions.row(0), Eigen::RowVector3d(1, 1, 0.5));
    EXPECT_EQ(p.positions.row(1), Eigen::RowVector3d(0.5, 1.5, 2));
    EXPECT_EQ(p.velocities.rows(), text == scaled ? 2 : 0);
  }
}

// `dump custom` writes its columns in the order the user names them. The velocities were
// taken as the three columns from vx on, so `vx fx vz vy` read fx as vy, and with vx last the
// reader indexed past the line's words.
TEST(PackingFile, DumpVelocitiesAreReadByTheirNamesInAnyOrder) {
  const std::string head =
      "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\n"
      "ITEM: BOX BOUNDS pp pp pp\n0 2\n0 2\n0 2\n";
  for (const std::string cols : {"id radius x y z vx fx vz vy", "vz vy id radius x y z vx"}) {
    const bool first = cols.front() == 'i';
    const std::string rows = first ? "1 0.2 0.5 0.5 0.5 1 9 3 2\n2 0.2 1.5 1.5 1.5 4 9 6 5\n"
                                   : "3 2 1 0.2 0.5 0.5 0.5 1\n6 5 2 0.2 1.5 1.5 1.5 4\n";
    const fs::path f = write("velocities.dump", head + "ITEM: ATOMS " + cols + "\n" + rows);
    const Packing p = rendulic::read_lammps_dump(f);
    ASSERT_EQ(p.velocities.rows(), 2) << cols;
    EXPECT_EQ(p.velocities.row(0), Eigen::RowVector3d(1, 2, 3)) << cols;
    EXPECT_EQ(p.velocities.row(1), Eigen::RowVector3d(4, 5, 6)) << cols;
  }
}

// `dump_modify units yes time yes` (LAMMPS writes them so) puts ITEM: UNITS (first snapshot
// only) and ITEM: TIME before a snapshot's timestep: such a dump was refused as "expected
// 'ITEM: TIMESTEP'". The unit style is kept for the warning that the numbers are read as SI.
TEST(PackingFile, DumpUnitsAndTimeItemsAreReadPast) {
  const std::string snapshot =
      "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 2\n0 2\n0 2\n"
      "ITEM: ATOMS id radius x y z\n1 0.2 0.5 0.5 0.5\n";
  const std::string text = "ITEM: UNITS\ncgs\nITEM: TIME\n0\n" + snapshot +
                           "ITEM: TIME\n1.5000000000000000e-08\n" + snapshot;
  const Packing p = rendulic::read_lammps_dump(write("units.dump", text));
  EXPECT_EQ(p.units, "cgs");
  EXPECT_EQ(p.size(), 1u);
  EXPECT_TRUE(rendulic::read_lammps_dump(write("plain.dump", snapshot)).units.empty());
}

// A dump cut anywhere in a snapshot's header says what is missing. The reader went on with an
// empty line: cut after "ITEM: NUMBER OF ATOMS" it said "the atom count must be positive",
// inside the box "a box line needs lo and hi", after the timestep "expected 'ITEM: NUMBER OF
// ATOMS'" on the timestep's line.
TEST(PackingFile, ADumpCutInItsHeaderSaysWhatIsMissing) {
  const std::vector<std::string> lines = {"ITEM: TIMESTEP",
                                          "0",
                                          "ITEM: NUMBER OF ATOMS",
                                          "1",
                                          "ITEM: BOX BOUNDS pp pp pp",
                                          "0 2",
                                          "0 2",
                                          "0 2",
                                          "ITEM: ATOMS id radius x y z"};
  const std::vector<std::string> missing = {"the snapshot's timestep", "'ITEM: NUMBER OF ATOMS'",
                                            "the atom count",          "'ITEM: BOX BOUNDS'",
                                            "the box's x bounds",      "the box's y bounds",
                                            "the box's z bounds",      "'ITEM: ATOMS'"};
  for (std::size_t cut = 1; cut < lines.size(); ++cut) {
    std::string text;
    for (std::size_t k = 0; k < cut; ++k) text += lines[k] + "\n";
    const fs::path f = write("cut.dump", text);
    const std::string want =
        f.string() + ":" + std::to_string(cut) + ": the file ends before " + missing[cut - 1];
    try {
      rendulic::read_lammps_dump(f);
      ADD_FAILURE() << "read a dump cut after line " << cut;
    } catch (const rendulic::InputError& e) {
      EXPECT_EQ(e.what(), want);
    }
  }
  try {
    rendulic::read_lammps_dump(write("step.dump", "ITEM: TIMESTEP\nstep\n"));
    ADD_FAILURE() << "read a timestep that is not an integer";
  } catch (const rendulic::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":2: timestep 'step' is not an integer"),
              std::string::npos)
        << e.what();
  }
}

TEST(PackingFile, WriterIsReadBackToTheSameDoubles) {
  Packing p;
  p.lengths = Eigen::Vector3d(0.1, std::sqrt(0.02), 1.0 / 3.0);
  p.positions.resize(4, 3);
  p.velocities.resize(4, 3);
  for (int i = 0; i < 4; ++i)
    for (int a = 0; a < 3; ++a) {
      p.positions(i, a) = std::fmod(std::sqrt(2.0 + i + 3 * a), 1.0) * p.lengths[a];
      p.velocities(i, a) = std::sin(1.0 + i - a);
    }
  p.radii = {1.0 / 77, 1.0 / 91, std::sqrt(1e-5), 0.0123456789012345};
  const fs::path f = write("round.data", "");
  rendulic::write_lammps_data(f, p, 2500, "round trip");
  const Packing q = rendulic::read_lammps_data(f);
  EXPECT_EQ(q.radii, p.radii);
  EXPECT_TRUE(q.positions == p.positions);
  EXPECT_TRUE(q.velocities == p.velocities);
  EXPECT_EQ(q.lengths, p.lengths);
  EXPECT_EQ(q.densities, std::vector<double>(4, 2500));
}

TEST(PackingFile, AResultsFileArgumentNeedsAState) {
  const fs::path f = write("fake.h5", "\x89HDF\r\n");
  EXPECT_THROW(rendulic::packing_source(f.string()), rendulic::InputError);
  const rendulic::PackingSource s = rendulic::packing_source(f.string() + ":b");
  EXPECT_EQ(s.format, rendulic::PackingFormat::kResultsState);
  EXPECT_EQ(s.object, "/states/b");
  EXPECT_EQ(rendulic::packing_label(s, "imported"), "b");
  EXPECT_THROW(rendulic::packing_source(f.string() + ":"), rendulic::InputError);
}

}  // namespace
