#pragma once
// Vectorised material updates (Google Highway, run-time dispatch; core/simd_dispatch.hpp): the
// linear elastic update and the Drucker–Prager update of a run of particles of one body, several
// particles per instruction. Each lane does the operations of the scalar reference
// (BodyMaterials' per-particle update, DruckerPrager::update) in the same order, so every
// instruction set gives the reference's bits. Drucker–Prager's returns to the cone, the tension
// cut-off, their corner and the apex all run in the lanes. A group of particles that needs a branch
// the kernel does not vectorise (a non-finite value, an apex value that ties with the cut-off) is
// left to the scalar reference: the kernel stops before it and says how many particles the reference
// must take. Separated particles (BodyMaterials' separation rule) and, for μ(I), disconnected ones
// run in the lanes.
#include <array>
#include <cstddef>

namespace talus {

/// The particle arrays of one chunk and its increments (increment k belongs to particle chunk_begin + k).
struct MaterialKernelFields {
  std::array<double*, 6> stress{}, strain{};
  double* volume = nullptr;
  const double* volume0 = nullptr;
  double* plastic_strain = nullptr;
  std::array<const double*, 6> strain_increment{};
  std::array<const double*, 3> spin{};  // w_yz, w_xz, w_xy
  std::size_t chunk_begin = 0;
};

struct ElasticKernelConstants {
  double lambda = 0.0, shear = 0.0;
};

/// Drucker–Prager without kinematic hardening (the back stress is zero): the constants of the two
/// models of a granular body, [0] before it flows and [1] once it flows (they differ in alpha_g).
struct DruckerPragerKernelConstants {
  double shear = 0.0, lame = 0.0, alpha = 0.0, initial_strength = 0.0, hardening_isotropic = 0.0;
  double shear_plus_kinematic = 0.0;       // G + H_kin (0 kinematic hardening here: G)
  double first_invariant_cutoff = 0.0;     // may be +inf
  double separation_volume_ratio = 0.0;    // 0: no separation rule
  double separated_two_bulk = 0.0, separated_four_shear = 0.0;  // the body's 2 K and 4 G (the energy it releases)
  double flowing_plastic_strain = 0.0;
  std::array<double, 2> cone_denominator{};  // G + 9 K alpha alpha_g + H
  std::array<double, 2> dilation_factor{};   // 9 K alpha_g
  std::array<double, 2> alpha_excess{};      // alpha - alpha_g
  // the tension cut-off and the apex (DruckerPrager::plastic_return, steps 4-5), as it writes them
  double three_bulk = 0.0;                   // 3.0 * K
  double corner_denominator = 0.0;           // G + H_kin + H_iso
  double two_shear_plus_kinematic = 0.0;     // 2.0 * (G + H_kin)
};

/// μ(I) (Jop et al. 2006 in the form of Dunatunga & Kamrin 2015; material/mu_i.hpp) for one time step.
struct MuIKernelConstants {
  double shear = 0.0, lame = 0.0, bulk = 0.0, mu_s = 0.0, mu_2 = 0.0, i0 = 0.0;
  double friction_rise = 0.0;            // mu_2 - mu_s
  double rate_constant = 0.0;            // d sqrt(rho_s) / G
  double separation_volume_ratio = 0.0;  // 0: no separation rule
  double separated_two_bulk = 0.0, separated_four_shear = 0.0;  // the body's 2 K and 4 G (the energy it releases)
  double dt = 0.0;
};

/// Where a kernel stopped: particles [begin, next) are done; the scalar reference must take the
/// next `scalar_count` particles (a group it does not vectorise, or the tail shorter than a group)
/// before the kernel can go on.
struct KernelStop {
  std::size_t next = 0;
  std::size_t scalar_count = 0;
};

/// Particles [begin, end) of a linear elastic body: volume, Hughes–Winget rotation, Hooke, strain.
KernelStop update_elastic_lanes(const MaterialKernelFields& fields, const ElasticKernelConstants& constants,
                                std::size_t begin, std::size_t end);

/// Particles [begin, end) of a Drucker–Prager body (no back stress): adds each particle's
/// dissipation V sigma : d_eps^p to `dissipated` in particle order.
KernelStop update_drucker_prager_lanes(const MaterialKernelFields& fields,
                                       const DruckerPragerKernelConstants& constants, std::size_t begin,
                                       std::size_t end, double& dissipated);

/// Particles [begin, end) of a μ(I) body: adds each particle's dissipation to `dissipated` in
/// particle order; a group with a separated or disconnected (p <= 0) particle goes to the reference.
KernelStop update_mu_i_lanes(const MaterialKernelFields& fields, const MuIKernelConstants& constants, std::size_t begin,
                             std::size_t end, double& dissipated);

}  // namespace talus
