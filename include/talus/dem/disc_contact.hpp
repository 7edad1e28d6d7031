#pragma once
// The contact law between two discs of radius a and the macroscopic stress that the contact forces
// of one disc represent (Abe 1996, eq. 1-3 and 50). 2D, forces per unit depth.
//
// Sign conventions (Abe 1996, Fig. 2): n points from disc A's centre to the contact with B,
// s = (-n_y, n_x) is n turned a quarter turn anticlockwise, rotations are anticlockwise positive and
// u_BA = u_B - u_A. Stress is positive in tension.
#include "talus/dem/contact_calibration.hpp"

#include <Eigen/Core>

#include <span>

namespace talus::dem {

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;

inline Vec2 tangent_of(const Vec2& normal) { return {-normal.y(), normal.x()}; }

/// Force and moment that disc B exerts on disc A.
struct ContactLoad {
  Vec2 force = Vec2::Zero();  // F_N + F_T (Abe 1996, eq. 1, 2)
  double moment = 0.0;        // M (Abe 1996, eq. 3), about A's centre
};

/// Abe 1996, eq. 1-3: the springs see the relative displacement of the two contact points,
/// u_BA . n normally and u_BA . s - a (theta_A + theta_B) tangentially.
ContactLoad contact_load(const ContactSprings& springs, const Vec2& normal, const Vec2& relative_displacement,
                         double rotation_a, double rotation_b, double radius);

/// One contact as seen from the disc whose stress is evaluated.
struct ContactForce {
  Vec2 force;   // force on the disc
  Vec2 normal;  // unit vector from the disc's centre to the contact point
};

/// Abe 1996, eq. 50: sigma_ij = (gamma/rho) / (pi a) sum_contacts F_i n_j. Symmetric only when the
/// disc's moments balance (free rotation, eq. 7); see Abe 1996, eq. 55 for rotation-locked discs.
Mat2 disc_contact_stress(std::span<const ContactForce> contacts, double radius, double density_ratio);

}  // namespace talus::dem
