// The FIRE minimiser's contact forces (probe_minimise.cpp; docs/performance.md "FIRE's
// forces and the probe tools' pair search"): the net spring force on every particle of a
// packing at rest from a list of candidate pairs. Internal to the dem module's sources.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "rendulic/dem/contact.hpp"
#include "rendulic/dem/dem_system.hpp"
#include "rendulic/dem/probe_geometry.hpp"

namespace rendulic::dem {

// A candidate pair as the force loop reads it: its indices alone (find_pairs' geometry is that
// of the configuration the list was built at; 8 bytes per pair streamed, not 48).
struct FirePair {
  std::int32_t i, j;
};

// The packing's positions and radii as 4-double records, made at each evaluation, and the
// forces being summed, one record per particle (one cache line per particle and side of a pair,
// not the three of an N x 3 matrix's columns).
struct FireScratch {
  AlignedVector record, force;
};

// The net forces (N x 3) of the touching pairs of `pairs` (i < j, in find_pairs' order (i, j),
// each pair's force added to i and subtracted from j in that order); returns the elastic
// energy, with the sum of the contact forces and their number. h_inv = packing.cell.h^-1.
double fire_contact_forces(const PackingData& packing, const Eigen::Matrix3d& h_inv,
                           const std::vector<FirePair>& pairs, const NormalContact& law,
                           FireScratch& scratch, Eigen::MatrixX3d& force, double* sum_contact_force,
                           int* n_contacts);

}  // namespace rendulic::dem
