#pragma once
// The macroscopic stress (Abe 1996, eq. 50) of an infinite hexagonal disc lattice whose centres follow
// a uniform displacement gradient. With free rotations every disc turns by the moment-balance angle
// theta = (u_2,1 - u_1,2)/2 (Abe 1996, eq. 15 with C_mk/C = delta_mk/2), and the result must equal the
// isotropic law eq. 52 for the eq. 34 springs; with locked rotations it is eq. 55 (not symmetric).
// An affine field is an exact equilibrium state of every disc of a centro-symmetric lattice, so no
// Taylor truncation enters: tests compare against eq. 52 to rounding error.
#include "talus/dem/disc_contact.hpp"

#include <array>

namespace talus::dem {

/// Unit vectors from a disc to its six neighbours in a lattice with horizontal rows (Abe 1996, Fig. 5).
std::array<Vec2, 6> hexagonal_contact_normals();

/// Disc rotation that balances the contact moments under a uniform gradient (Abe 1996, eq. 15).
double balancing_rotation(const Mat2& displacement_gradient);

struct LatticeResponse {
  std::array<ContactForce, 6> contacts;  // forces on the reference disc
  double rotation = 0.0;                 // its rotation theta
  double moment_sum = 0.0;               // sum of contact moments (0 with free rotations)
  Mat2 stress = Mat2::Zero();            // Abe 1996, eq. 50
};

/// displacement_gradient(i, j) = du_i/dx_j.
LatticeResponse hexagonal_lattice_response(const ContactSprings& springs, const Mat2& displacement_gradient,
                                           double radius, bool rotations_locked);

}  // namespace talus::dem
