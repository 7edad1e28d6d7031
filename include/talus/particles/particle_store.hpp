#pragma once
// ParticleStore: every particle field as its own contiguous array (structure of arrays), so the
// phase loops stream through memory and vectorise. Particles are kept sorted by cell (see
// cell_sort.hpp); the permutation is applied to every field, and `id` keeps each particle's
// identity across sorts. Field groups a scene does not need are left empty (size 0).
#include "talus/core/staggered_allocator.hpp"
#include "talus/core/types.hpp"
#include "talus/particles/particle_scratch.hpp"

#include <array>
#include <string_view>
#include <cstdint>
#include <span>
#include <vector>

namespace talus {

struct ParticleStore {
  // Always present.
  ParticleArray<std::int64_t> id;               // stable identity, assigned at seeding
  std::array<ParticleArray<double>, 3> x;       // position [m]
  std::array<ParticleArray<double>, 3> v;       // velocity [m/s]
  ParticleArray<double> mass;                   // [kg], constant
  ParticleArray<double> volume;                 // current volume [m^3] (Edo & Matsubara 2015, eq. 35)
  ParticleArray<double> volume0;                // volume at seeding [m^3] (sets the GIMP domain)
  std::array<ParticleArray<double>, 6> stress;  // Cauchy stress, Voigt xx yy zz yz xz xy [Pa]
  std::array<ParticleArray<double>, 6> strain;  // accumulated (log-like) strain, tensor components
  ParticleArray<std::uint16_t> body;            // index into Scene::bodies

  // Drucker-Prager state: allocated only when some body uses that material.
  ParticleArray<double> plastic_strain;            // equivalent plastic strain
  std::array<ParticleArray<double>, 6> back_stress;  // kinematic hardening centre [Pa]; only with kinematic hardening

  // cpGIMP particle domain: current half widths per axis [m] (Edo & Matsubara 2015, eq. 57-58); allocated only
  // when the scene uses cpGIMP.
  std::array<ParticleArray<double>, 3> domain;

  std::size_t size() const { return id.size(); }
  bool has_plastic_state() const { return plastic_enabled_; }
  bool has_domain_state() const { return domain_enabled_; }

  /// Append one particle with zero stress and strain; returns its index.
  std::size_t add(std::int64_t particle_id, const Vec3& position, const Vec3& velocity,
                  double particle_mass, double particle_volume, std::uint16_t body_index);

  /// Reserve room for n particles in the arrays add() fills, so seeding grows none of them.
  void reserve(std::size_t n);

  /// Allocate (zeroed) the plastic state arrays for all particles.
  /// The back stress only with `with_back_stress`: it stays zero unless some body has kinematic
  /// hardening (H > 0 and kinematic_fraction > 0), and then costs 48 B per particle for nothing.
  void enable_plastic_state(bool with_back_stress = true);
  bool has_back_stress() const { return back_stress_enabled_; }
  /// Whether the store's layout (the scene's) has the double array `name` (for_each_double_array's
  /// names): the optional groups by their flags, for a store of any size, even none (a rank whose
  /// slab seeded no particle has every array empty).
  bool has_array(std::string_view name) const {
    if (name == "plastic_strain") return plastic_enabled_;
    if (name.starts_with("back_stress")) return back_stress_enabled_;
    if (name.starts_with("domain")) return domain_enabled_;
    return true;
  }

  /// Allocate the cpGIMP domain half widths, each set to its initial value V0^(1/3)/2.
  void enable_domain_state();

  /// Apply a gather permutation to every allocated field: new[i] = old[order[i]]. `order` may be
  /// shorter than the store (a subset: the particles that stay). Each field is gathered into planes
  /// `plane` and `plane` + 1 of `scratch` (even `plane`; `order` must not lie there) and copied back,
  /// so the fields keep their memory and a sort allocates nothing.
  void permute(std::span<const std::uint32_t> order, ParticleScratch& scratch, int plane);
  /// The same with a scratch of its own (rare reorders: outflow, migration, a checkpoint's subset).
  void permute(std::span<const std::uint32_t> order);

  /// Make this store a copy of `other` (its arrays and state flags), each
  /// array copied by all threads in static slices: the run loop's last-good-state snapshot copies
  /// every particle every few steps, and a serial copy is a serial part of every step at many cores.
  void copy_from(const ParticleStore& other);

  /// Bytes held by particle fields (capacity, all allocated groups), for the memory report.
  std::size_t bytes() const;

  /// Visit every per-particle double array under a stable name: f(const char* name, vector<double>&).
  /// Components are numbered: "x0" "x1" "x2", "v0".., "stress0".."stress5" (Voigt order above).
  /// Arrays a scene does not use are visited too, empty; callers skip those.
  /// The checkpoint (io/checkpoint.cpp) and the finite-value guard (solver/stability_guards.cpp)
  /// walk the particles through this visitor only: A NEW PER-PARTICLE ARRAY IS CHECKPOINTED AND
  /// GUARDED BY ADDING ONE LINE HERE (permute() and bytes() walk it too).
  template <class F>
  void for_each_double_array(F&& f) {
    visit_double_arrays(*this, f);
  }
  template <class F>
  void for_each_double_array(F&& f) const {
    visit_double_arrays(*this, f);
  }
  /// The integer arrays: f("id", id) and f("body", body) (element types int64 and uint16).
  template <class F>
  void for_each_integer_array(F&& f) {
    f("id", id);
    f("body", body);
  }
  template <class F>
  void for_each_integer_array(F&& f) const {
    f("id", id);
    f("body", body);
  }

 private:
  template <class Store, class F>
  static void visit_double_arrays(Store& s, F& f) {
    static const char* const kVec[3][3] = {{"x0", "x1", "x2"}, {"v0", "v1", "v2"}, {"", "", ""}};
    static const char* const kSym[3][6] = {{"stress0", "stress1", "stress2", "stress3", "stress4", "stress5"},
                                           {"strain0", "strain1", "strain2", "strain3", "strain4", "strain5"},
                                           {"back_stress0", "back_stress1", "back_stress2", "back_stress3",
                                            "back_stress4", "back_stress5"}};
    for (int d = 0; d < 3; ++d) f(kVec[0][d], s.x[d]);
    for (int d = 0; d < 3; ++d) f(kVec[1][d], s.v[d]);
    f("mass", s.mass);
    f("volume", s.volume);
    f("volume0", s.volume0);
    for (int c = 0; c < 6; ++c) f(kSym[0][c], s.stress[c]);
    for (int c = 0; c < 6; ++c) f(kSym[1][c], s.strain[c]);
    f("plastic_strain", s.plastic_strain);
    for (int c = 0; c < 6; ++c) f(kSym[2][c], s.back_stress[c]);
    f("domain0", s.domain[0]);
    f("domain1", s.domain[1]);
    f("domain2", s.domain[2]);
  }

  bool plastic_enabled_ = false;
  bool back_stress_enabled_ = false;
  bool domain_enabled_ = false;
};

}  // namespace talus
