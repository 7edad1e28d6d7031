#include "talus/dem/disc_contact.hpp"

#include <numbers>

namespace talus::dem {

ContactLoad contact_load(const ContactSprings& springs, const Vec2& normal, const Vec2& relative_displacement,
                         double rotation_a, double rotation_b, double radius) {
  const Vec2 tangent = tangent_of(normal);
  const double normal_opening = relative_displacement.dot(normal);
  // The contact point of A moves by a theta_A s, that of B by -a theta_B s (it sits at -a n from B).
  const double tangential_slip = relative_displacement.dot(tangent) - radius * (rotation_a + rotation_b);
  ContactLoad load;
  load.force = springs.normal * normal_opening * normal + springs.tangential * tangential_slip * tangent;
  load.moment = springs.tangential * radius * tangential_slip;  // a n x F_T, with n x s = 1
  return load;
}

Mat2 disc_contact_stress(std::span<const ContactForce> contacts, double radius, double density_ratio) {
  Mat2 sum = Mat2::Zero();
  for (const ContactForce& contact : contacts) sum += contact.force * contact.normal.transpose();
  return density_ratio / (std::numbers::pi * radius) * sum;  // Abe 1996, eq. 50
}

}  // namespace talus::dem
