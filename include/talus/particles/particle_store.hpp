#pragma once
// ParticleStore: every particle field as its own contiguous array (structure of arrays), so the
// phase loops stream through memory and vectorise. Particles are kept sorted by cell (see
// cell_sort.hpp); the permutation is applied to every field, and `id` keeps each particle's
// identity across sorts. Field groups a scene does not need are left empty (size 0).
#include "talus/core/types.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace talus {

struct ParticleStore {
  // Always present.
  std::vector<std::int64_t> id;               // stable identity, assigned at seeding
  std::array<std::vector<double>, 3> x;       // position [m]
  std::array<std::vector<double>, 3> v;       // velocity [m/s]
  std::vector<double> mass;                   // [kg], constant
  std::vector<double> volume;                 // current volume [m^3] (seed 000 eq. 35)
  std::vector<double> volume0;                // volume at seeding [m^3] (sets the GIMP domain)
  std::array<std::vector<double>, 6> stress;  // Cauchy stress, Voigt xx yy zz yz xz xy [Pa]
  std::array<std::vector<double>, 6> strain;  // accumulated (log-like) strain, tensor components
  std::vector<std::uint16_t> body;            // index into Scene::bodies

  // Drucker-Prager state: allocated only when some body uses that material.
  std::vector<double> plastic_strain;            // equivalent plastic strain
  std::array<std::vector<double>, 6> back_stress;  // kinematic hardening centre [Pa]

  std::size_t size() const { return id.size(); }
  bool has_plastic_state() const { return plastic_enabled_; }

  /// Append one particle with zero stress and strain; returns its index.
  std::size_t add(std::int64_t particle_id, const Vec3& position, const Vec3& velocity,
                  double particle_mass, double particle_volume, std::uint16_t body_index);

  /// Allocate (zeroed) the plastic state arrays for all particles.
  void enable_plastic_state();

  /// Apply a gather permutation to every allocated field: new[i] = old[order[i]].
  /// Reuses internal scratch arrays, so repeated sorts allocate nothing.
  void permute(const std::vector<std::uint32_t>& order);

  /// Bytes held by particle fields (capacity, all allocated groups), for the memory report.
  std::size_t bytes() const;

 private:
  bool plastic_enabled_ = false;
  std::vector<double> scratch_;
  std::vector<std::int64_t> id_scratch_;
  std::vector<std::uint16_t> body_scratch_;
};

}  // namespace talus
