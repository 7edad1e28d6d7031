#include "talus/dem/hex_lattice_stress.hpp"

#include <cmath>
#include <numbers>

namespace talus::dem {

std::array<Vec2, 6> hexagonal_contact_normals() {
  std::array<Vec2, 6> normals;
  for (int k = 0; k < 6; ++k) {
    const double angle = k * std::numbers::pi / 3.0;
    normals[k] = {std::cos(angle), std::sin(angle)};
  }
  return normals;
}

double balancing_rotation(const Mat2& displacement_gradient) {
  return 0.5 * (displacement_gradient(1, 0) - displacement_gradient(0, 1));
}

LatticeResponse hexagonal_lattice_response(const ContactSprings& springs, const Mat2& displacement_gradient,
                                           double radius, bool rotations_locked) {
  LatticeResponse response;
  response.rotation = rotations_locked ? 0.0 : balancing_rotation(displacement_gradient);
  const std::array<Vec2, 6> normals = hexagonal_contact_normals();
  for (int k = 0; k < 6; ++k) {
    // Abe 1996, eq. 8: the neighbour's centre is 2a n away, so an affine field moves it by 2a H n
    // relative to the reference disc; both discs turn by the same angle.
    const Vec2 relative = 2.0 * radius * displacement_gradient * normals[k];
    const ContactLoad load =
        contact_load(springs, normals[k], relative, response.rotation, response.rotation, radius);
    response.contacts[k] = {load.force, normals[k]};
    response.moment_sum += load.moment;
  }
  response.stress = disc_contact_stress(response.contacts, radius, kHexagonalDensityRatio);
  return response;
}

}  // namespace talus::dem
