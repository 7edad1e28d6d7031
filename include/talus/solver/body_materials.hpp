#pragma once
// BodyMaterials: the constitutive update of every body, chosen per body from the scene
// (linear elastic or Drucker-Prager), applied to a chunk of particles after their strain
// increments are known. The solver calls it between the strain pass and the particle motion;
// it knows nothing of grids or shape functions.
//
// Per particle and step (objective update, docs/theory.md):
//   sigma <- R sigma R^T (Hughes-Winget rotation by the spin increment; also the back stress)
//   sigma <- material(sigma, d_eps)                 (Edo & Matsubara 2015, eq. 34 / Abe, Johansson & Konagai 2005, eq. 23-25)
//   strain += d_eps, V <- V (1 + tr d_eps)         (Edo & Matsubara 2015, eq. 35)
// Drucker-Prager bodies add the granular rules of a runout scene (scene.hpp GranularOptions):
// psi -> flowing_dilatancy_angle once eps_p > flowing_plastic_strain, and stress-free, virgin
// particles once V / V0 > separation_volume_ratio. μ(I) bodies (docs/mu-i.md) keep the separation
// rule and need the time step: their strength depends on the shear rate.
#include "talus/material/drucker_prager.hpp"
#include "talus/material/linear_elastic.hpp"
#include "talus/material/mu_i.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"
#include "talus/solver/material_kernels.hpp"
#include "talus/solver/time_step_scan.hpp"
#include "talus/transfer/transfers.hpp"

#include <cstddef>
#include <vector>

namespace talus {

class BodyMaterials {
 public:
  /// Builds one model per body; allocates the particles' plastic state when any body is
  /// Drucker-Prager or μ(I) (and only then).
  BodyMaterials() = default;
  BodyMaterials(const Scene& scene, ParticleStore& particles);

  /// Update the stress, material state, strain and volume of particles [begin, end) from the
  /// increments `inc` (entry k belongs to particle begin + k) over the time step dt. Returns the energy the material
  /// dissipated in this chunk [J]: plastic work V sigma : d_eps^p plus the elastic energy dropped
  /// by separated particles. Deterministic: the sum runs in particle order.
  double update(ParticleStore& particles, std::size_t begin, std::size_t end, const StrainIncrements& inc,
                double dt) const;

  /// P-wave modulus K + 4G/3 of a body (sets the wave speed and the time step).
  double p_wave_modulus(std::size_t body) const { return bodies_[body].p_wave_modulus; }
  /// Stored elastic energy per unit volume of a stress in a body: p^2/(2K) + s:s/(4G).
  double stored_energy_density(std::size_t body, const Sym6& stress) const {
    return bodies_[body].elastic.energy_density(stress);
  }
  /// The volume that sets a particle's wave speed c = sqrt(M V / m). A separated Drucker-Prager
  /// particle carries no stress, so its further dilation must not shrink the time step: its
  /// volume counts at most as separation_volume_ratio V0 (the same for a μ(I) particle).
  double wave_speed_volume(std::size_t body, double volume, double volume0) const {
    const double ratio = bodies_[body].granular.separation_volume_ratio;
    const MaterialModel model = bodies_[body].model;
    return (model == MaterialModel::DruckerPrager || model == MaterialModel::MuI) && ratio > 0.0 &&
                   volume > ratio * volume0
               ? ratio * volume0
               : volume;
  }
  /// Whether every body has the same wave-speed rule (the same P-wave modulus and the same cap on
  /// the volume); then `rule` is that rule, for the time step's vectorised scan.
  bool shared_wave_rate_rule(WaveRateRule& rule) const;

 private:
  struct Body {
    MaterialModel model = MaterialModel::LinearElastic;
    LinearElastic elastic;
    double p_wave_modulus = 0.0;
    // Drucker-Prager only:
    std::vector<DruckerPrager> plastic;  // [0] as given, [1] with the flowing dilatancy angle
    GranularOptions granular;  // and μ(I): separation_volume_ratio
    std::vector<MuI> mu_i;     // μ(I) only: one model
    DruckerPragerKernelConstants drucker_prager_lanes;  // the vector kernel's copy of `plastic`
    MuIKernelConstants mu_i_lanes;                      // and of `mu_i` (dt set per update)
  };
  static bool separated(const Body& body, const ParticleStore& P, std::size_t p);
  static double release_separated(const Body& body, ParticleStore& P, std::size_t p, Sym6& stress);
  double update_mu_i(const Body& body, ParticleStore& P, std::size_t p, Sym6& stress, const Sym6& d_eps, double w_yz,
                     double w_xz, double w_xy, double dt) const;
  double update_drucker_prager(const Body& body, ParticleStore& P, std::size_t p, Sym6& stress, const Sym6& d_eps,
                               double w_yz, double w_xz, double w_xy) const;
  /// The scalar reference update of particle p (increment k); returns its dissipation.
  double update_particle(const Body& body, ParticleStore& P, std::size_t p, const StrainIncrements& inc,
                         std::size_t k, double dt) const;
  /// Particles [begin, end) of one body: the vector kernel where it applies, else the reference.
  void update_run(const Body& body, ParticleStore& P, std::size_t begin, std::size_t end, std::size_t chunk_begin,
                  const StrainIncrements& inc, double dt, double& dissipated) const;

  std::vector<Body> bodies_;
  bool any_plastic_ = false;
  bool any_kinematic_ = false;  // some Drucker-Prager body with kinematic hardening (H > 0, kinematic_fraction > 0)
};

}  // namespace talus
