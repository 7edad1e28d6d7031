// Abe 1996, §4: the stress of eq. 50, evaluated from the contact forces of a hexagonal lattice under a
// uniform displacement gradient, is the isotropic law eq. 52 for the eq. 34 springs (free rotations)
// and the non-symmetric eq. 55 for rotation-locked discs.
#include "talus/dem/contact_calibration.hpp"
#include "talus/dem/hex_lattice_stress.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

namespace talus::dem {
namespace hex_lattice_stress_test {
namespace {

Mat2 isotropic_law(const IsotropicElasticity& m, const Mat2& strain) {  // Abe 1996, eq. 52
  const double nu = m.poisson_ratio;
  return m.shear_modulus * (2.0 * nu / (1.0 - 2.0 * nu) * strain.trace() * Mat2::Identity() + 2.0 * strain);
}

// Abe 1996, eq. 55 divided by the eq. 50 factor (gamma/rho)/(pi a) = 1/(2 sqrt3 a); u(i, j) = du_i/dx_j.
// The seed's text (as scanned) drops the kN delta_2i delta_2j (u11 + 3 u22) term; it follows from the
// same fourth-moment sum as the delta_1i delta_1j term.
Mat2 locked_rotation_law(const ContactSprings& k, const Mat2& u, double radius) {
  const double u11 = u(0, 0), u12 = u(0, 1), u21 = u(1, 0), u22 = u(1, 1);
  Mat2 normal_part;
  normal_part << 3.0 * u11 + u22, u12 + u21, u12 + u21, u11 + 3.0 * u22;
  Mat2 tangential_part;
  tangential_part << u11 - u22, 3.0 * u12 - u21, -u12 + 3.0 * u21, -(u11 - u22);
  const Mat2 sum = 1.5 * radius * (k.normal * normal_part + k.tangential * tangential_part);
  return sum / (2.0 * std::sqrt(3.0) * radius);
}

const PackingGeometry& hexagonal() {
  static const PackingGeometry geometry = make_packing_geometry(Packing::hexagonal);
  return geometry;
}

TEST(HexLatticeStress, FreeRotationStressIsTheIsotropicLawEq52) {
  std::srand(11);
  for (double nu : {-0.4, 0.0, 0.1, 0.25}) {
    const IsotropicElasticity target{5.0e6, nu};
    const ContactSprings springs = calibrate_contact_springs(target, hexagonal());
    for (int trial = 0; trial < 4; ++trial) {
      const Mat2 gradient = 1e-3 * Mat2::Random();  // includes a rigid rotation and shear
      const LatticeResponse response = hexagonal_lattice_response(springs, gradient, 0.02, false);
      const Mat2 strain = 0.5 * (gradient + gradient.transpose());
      const Mat2 expected = isotropic_law(target, strain);
      EXPECT_LT((response.stress - expected).norm(), 1e-12 * expected.norm()) << "nu = " << nu;
      EXPECT_NEAR(response.moment_sum, 0.0, 1e-12 * springs.normal * 0.02 * 0.02 * gradient.norm());
      EXPECT_NEAR(response.rotation, 0.5 * (gradient(1, 0) - gradient(0, 1)), 1e-18);
    }
  }
}

TEST(HexLatticeStress, RigidRotationCarriesNoStress) {
  const ContactSprings springs = calibrate_contact_springs({1.0, 0.1}, hexagonal());
  Mat2 spin;
  spin << 0.0, -1e-3, 1e-3, 0.0;
  EXPECT_LT(hexagonal_lattice_response(springs, spin, 1.0, false).stress.norm(), 1e-15);
  // Locked discs resist the same rotation: an antisymmetric stress appears (the moments that hold
  // the discs are what Abe 1996, §4(3) blames for it).
  const Mat2 locked = hexagonal_lattice_response(springs, spin, 1.0, true).stress;
  EXPECT_GT(std::abs(locked(0, 1) - locked(1, 0)), 1e-4);
}

TEST(HexLatticeStress, LockedRotationStressIsEq55AndNotSymmetric) {
  std::srand(5);
  for (double nu : {0.0, 0.2}) {
    const ContactSprings springs = calibrate_contact_springs({2.0e6, nu}, make_packing_geometry(Packing::hexagonal_rotation_locked));
    const Mat2 gradient = 1e-3 * Mat2::Random();
    const LatticeResponse response = hexagonal_lattice_response(springs, gradient, 0.5, true);
    const Mat2 expected = locked_rotation_law(springs, gradient, 0.5);
    EXPECT_LT((response.stress - expected).norm(), 1e-12 * expected.norm());
    EXPECT_GT(std::abs(response.stress(0, 1) - response.stress(1, 0)), 1e-3 * response.stress.norm());
  }
  // ...unless kT = 0 (nu = 1/4), as Abe 1996, §4(3) says.
  const ContactSprings normal_only{1.0, 0.0};
  const Mat2 stress = hexagonal_lattice_response(normal_only, Mat2::Random(), 1.0, true).stress;
  EXPECT_NEAR(stress(0, 1), stress(1, 0), 1e-15);
}

TEST(HexLatticeStress, WithoutRotationLockedAndFreeLatticesCarryTheSameStress) {
  // For a symmetric gradient the balancing rotation is zero, so locking changes nothing: a uniform
  // traction test cannot see the difference between eq. 34 and eq. 53 lattices with equal kT/kN.
  std::srand(3);
  const ContactSprings springs{1.0, 0.37};
  const Mat2 r = Mat2::Random();
  const Mat2 symmetric = 0.5 * (r + r.transpose());
  const Mat2 free = hexagonal_lattice_response(springs, symmetric, 1.0, false).stress;
  const Mat2 locked = hexagonal_lattice_response(springs, symmetric, 1.0, true).stress;
  EXPECT_LT((free - locked).norm(), 1e-14 * free.norm());
}

}  // namespace
}  // namespace hex_lattice_stress_test
}  // namespace talus::dem
