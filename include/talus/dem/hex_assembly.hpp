#pragma once
// The verification problem of Abe 1996, §3 (Fig. 6): a hexagonally close-packed block of discs under
// uniform horizontal tension, solved statically with a sparse stiffness matrix (Abe 1996 uses a
// matrix method instead of dynamic DEM for the same reason: to test eq. 34 without damping or time
// step effects).
//
// Layout: rows of discs of radius a touching their neighbours, row j at height sqrt3 a j, odd rows
// shifted right by a and one disc shorter, an odd number of rows (so the block is symmetric about its
// middle row). Loads and supports as in Abe 1996, §3: equal horizontal forces on the left- and
// right-most disc of every row (see HexLoading for an exact alternative), the vertical displacement of
// the bottom row and the horizontal one of the bottom-left disc fixed. sigma_11 is the sum of the end
// forces over the height of the block, taken as rows * sqrt3 a (each row carries a band sqrt3 a high,
// so that the area per disc 2 sqrt3 a^2 matches gamma/rho = pi/(2 sqrt3)). Strains come from the
// relative displacement of two discs A-B on the middle row and two discs C-D stacked on the middle
// column. Results and their reading: docs/dem.md §6.
#include "talus/dem/contact_calibration.hpp"
#include "talus/dem/disc_contact.hpp"

namespace talus::dem {

/// How the horizontal tension is applied.
enum class HexLoading {
  // Abe 1996, §3: the same horizontal force on the outermost disc of every row. These forces differ
  // from the contact forces of a uniform stress state by a self-equilibrated set concentrated at the
  // block's ends and corners, which leaves an O(a / block size) disturbance in the middle.
  equal_end_forces,
  // Every boundary disc gets the force and moment that its missing neighbours would exert in the
  // uniform uniaxial stress state of the eq. 52 continuum (plane strain, G and nu from eq. 22 and 33).
  // The exact discrete solution is then uniform, which checks the solver to rounding error.
  uniform_stress_tractions,
};

struct HexAssemblySpec {
  int rows = 21;
  int discs_per_row = 21;
  double radius = 1.0;
  ContactSprings springs{1.0, 1.0};
  double applied_stress = 1.0;  // sigma_11; the problem is linear, so this only scales the answer
  bool rotations_locked = false;
  HexLoading loading = HexLoading::equal_end_forces;
  int gauge_columns = 4;    // A, B are the middle row's discs at middle column -/+ gauge_columns
  int gauge_row_pairs = 2;  // C, D are the middle column's discs at middle row -/+ 2 gauge_row_pairs
};

struct HexAssemblyResult {
  double strain_11 = 0.0;        // (u1_B - u1_A) / (x_B - x_A)
  double strain_22 = 0.0;        // (u2_D - u2_C) / (y_D - y_C)
  double poisson_ratio = 0.0;    // Abe 1996, eq. 35: -eps22 / (eps11 - eps22)
  double stiffness_ratio = 0.0;  // Abe 1996, eq. 36: sigma_11 / (kN eps11) = 2G / ((1 - nu) kN)
  Mat2 centre_stress = Mat2::Zero();  // Abe 1996, eq. 50 on the middle disc
  Mat2 centre_strain = Mat2::Zero();  // symmetric gradient fitted to the middle disc's six neighbours
  double centre_rotation = 0.0;       // rotation of the middle disc
  int unknowns = 0;                   // size of the solved system
};

/// Solves the assembly. Throws std::invalid_argument for a block too small for its gauges and
/// std::runtime_error when the stiffness matrix is singular (e.g. kT = -kN, where G = 0).
HexAssemblyResult analyse_hex_assembly(const HexAssemblySpec& spec);

}  // namespace talus::dem
