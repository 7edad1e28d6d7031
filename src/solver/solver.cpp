#include "talus/solver/solver.hpp"

#include "talus/core/deterministic_sum.hpp"
#include "talus/core/error.hpp"
#include "talus/core/tensor.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/shape/linear.hpp"
#include "talus/solver/grid_update.hpp"
#include "talus/transfer/transfers.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace talus {

Solver::Solver(Scene scene) : scene_(std::move(scene)) {
  particles_ = seed_particles(scene_);
  grid_ = Grid(scene_.grid);
  sort_ = CellSort(grid_, LinearShape::kReachLow, LinearShape::kReachHigh);
  walls_ = Walls(scene_.walls, scene_.grid);
  for (const BodySpec& b : scene_.bodies) {
    const MaterialSpec& m = scene_.materials[b.material];
    body_elastic_.push_back(LinearElastic::from_young_poisson(m.elastic.young, m.elastic.poisson));
    body_p_wave_modulus_.push_back(m.p_wave_modulus());
  }
  for (auto& d : displacement_) d.assign(particles_.size(), 0.0);
  // Nodes lighter than this are empty: far below any real nodal mass, far above round-off.
  mass_floor_ = 1e-12 * *std::min_element(particles_.mass.begin(), particles_.mass.end());
  sort_particles();
}

void Solver::sort_particles() {
  ScopedPhase timer(times_, Phase::Sort);
  sort_.sort(particles_, grid_);
  needs_sort_ = false;
  steps_since_sort_ = 0;
  ++sorts_;
}

bool Solver::finished() const {
  const bool time_done = time_ >= scene_.end_time * (1.0 - 1e-12);
  const bool steps_done = scene_.max_steps > 0 && step_ >= scene_.max_steps;
  return time_done || steps_done;
}

double Solver::stable_time_step() const {
  const ParticleStore& P = particles_;
  const std::size_t n = P.size();
  double max_rate = 0.0;  // max (c_p + |v_p|)
#pragma omp parallel for schedule(static) reduction(max : max_rate)
  for (std::size_t p = 0; p < n; ++p) {
    const double c = std::sqrt(body_p_wave_modulus_[P.body[p]] * P.volume[p] / P.mass[p]);
    const double speed = std::sqrt(P.v[0][p] * P.v[0][p] + P.v[1][p] * P.v[1][p] + P.v[2][p] * P.v[2][p]);
    max_rate = std::max(max_rate, c + speed);
  }
  return scene_.courant * scene_.grid.h / max_rate;  // seed 000 eq. 60
}

void Solver::step() {
  double dt = stable_time_step();
  if (!std::isfinite(dt) || dt <= 0.0)
    throw instability_error(fmt::format("step {}, t = {:.6g} s: time step {} is not positive and finite", step_, time_, dt));
  const double remaining = scene_.end_time - time_;
  if (dt > remaining) dt = remaining;
  switch (scene_.shape) {
    case ShapeKind::Linear: step_with<LinearShape, FlatTerrain>(dt); break;
  }
  time_ += dt;
  ++step_;
  last_dt_ = dt;
}

// One explicit step. MUSL (seed 000 eq. 47-56): P2G, grid update, G2P, momentum remap, strain and
// stress from the remapped velocities. USL differs only in skipping the remap (strain from v^L).
template <class Shape, class Terrain>
void Solver::step_with(double dt) {
  // 1. sort: when a particle has drifted beyond its block's slack, and every sort_interval steps
  //    to keep the memory order close to the cell order.
  if (needs_sort_ || steps_since_sort_ >= scene_.sort_interval) sort_particles();
  ++steps_since_sort_;

  // 2. P2G: nodal mass, momentum and internal force.
  {
    ScopedPhase timer(times_, Phase::P2G);
    grid_.clear_active();
    scatter_to_grid<Shape, Terrain>(particles_, sort_, grid_, ScatterFields::MassMomentumForce);
  }
  // 3. grid: velocities, accelerations with gravity, walls.
  {
    ScopedPhase timer(times_, Phase::Grid);
    friction_work_ += update_grid(grid_, walls_, scene_.gravity, dt, mass_floor_);
  }
  // 4. G2P: particle velocities and this step's displacement.
  {
    ScopedPhase timer(times_, Phase::G2P);
    const GatherResult r = gather_from_grid<Shape, Terrain>(particles_, sort_, grid_, dt, displacement_);
    if (r.nonfinite >= 0) report_bad_particle(r.nonfinite, "velocity is not finite");
    if (r.outside >= 0) report_bad_particle(r.outside, "left the grid");
    needs_sort_ = r.needs_sort;
  }
  // 5. remap (MUSL): v_i^{k+1} = sum m_p v_p N_i / m_i, with the walls (seed 000 eq. 52).
  std::array<const double*, 3> node_velocity = {grid_.velocity_l[0].data(), grid_.velocity_l[1].data(),
                                                grid_.velocity_l[2].data()};
  if (scene_.scheme == SchemeKind::Musl) {
    ScopedPhase timer(times_, Phase::Remap);
    grid_.clear_momentum();
    scatter_to_grid<Shape, Terrain>(particles_, sort_, grid_, ScatterFields::Momentum);
    velocities_from_momentum(grid_, walls_, mass_floor_);
    node_velocity = {grid_.momentum[0].data(), grid_.momentum[1].data(), grid_.momentum[2].data()};
  }
  // 6. strain and stress, then move the particles.
  {
    ScopedPhase timer(times_, Phase::Stress);
    update_stress<Shape, Terrain>(node_velocity, dt);
  }
}

// Strain increments are gathered for a chunk of particles into a small buffer, then the material
// update runs over the chunk: the gather stays cache-friendly and the update loop is simple.
template <class Shape, class Terrain>
void Solver::update_stress(const std::array<const double*, 3>& node_velocity, double dt) {
  ParticleStore& P = particles_;
  const std::size_t blocks = sort_.block_count();
#pragma omp parallel
  {
    StrainIncrements inc;
#pragma omp for schedule(dynamic, 1)
    for (std::size_t b = 0; b < blocks; ++b) {
      for (std::size_t begin = sort_.block_begin(b); begin < sort_.block_end(b); begin += StrainIncrements::kCapacity) {
        const std::size_t end = std::min<std::size_t>(begin + StrainIncrements::kCapacity, sort_.block_end(b));
        strain_increments<Shape, Terrain>(P, grid_, node_velocity, dt, begin, end, inc);
        for (std::size_t p = begin; p < end; ++p) {
          const std::size_t k = p - begin;
          Sym6 s, de;
          for (int c = 0; c < 6; ++c) {
            s[c] = P.stress[c][p];
            de[c] = inc.strain[c][k];
          }
          rotate_objectively(s, inc.spin[0][k], inc.spin[1][k], inc.spin[2][k]);  // Jaumann rate, Hughes-Winget
          body_elastic_[P.body[p]].add_increment(s, de);  // seed 000 eq. 34
          for (int c = 0; c < 6; ++c) {
            P.stress[c][p] = s[c];
            P.strain[c][p] += de[c];
          }
          P.volume[p] *= 1.0 + trace(de);  // seed 000 eq. 35: rho_new = rho / (1 + tr d_eps)
          for (int d = 0; d < 3; ++d) P.x[d][p] += displacement_[d][p];
        }
      }
    }
  }
}

EnergyBudget Solver::energies() const {
  const ParticleStore& P = particles_;
  const Vec3 g = scene_.gravity;
  const auto sums = deterministic_sum<3>(P.size(), [&](std::size_t p, std::array<double, 3>& acc) {
    const double v2 = P.v[0][p] * P.v[0][p] + P.v[1][p] * P.v[1][p] + P.v[2][p] * P.v[2][p];
    acc[0] += 0.5 * P.mass[p] * v2;
    Sym6 s;
    for (int c = 0; c < 6; ++c) s[c] = P.stress[c][p];
    acc[1] += P.volume[p] * body_elastic_[P.body[p]].energy_density(s);
    acc[2] -= P.mass[p] * (g[0] * P.x[0][p] + g[1] * P.x[1][p] + g[2] * P.x[2][p]);
  });
  EnergyBudget e;
  e.kinetic = sums[0];
  e.strain = sums[1];
  e.gravity = sums[2];
  e.friction_work = friction_work_;
  e.plastic_work = plastic_work_;
  return e;
}

void Solver::report_bad_particle(long long index, const char* what) const {
  const auto p = static_cast<std::size_t>(index);
  const ParticleStore& P = particles_;
  throw instability_error(fmt::format(
      "step {}, t = {:.6g} s: particle {} (body \"{}\") {}: position ({:.6g}, {:.6g}, {:.6g}) m, velocity ({:.6g}, "
      "{:.6g}, {:.6g}) m/s",
      step_, time_, P.id[p], scene_.bodies[P.body[p]].name, what, P.x[0][p], P.x[1][p], P.x[2][p], P.v[0][p],
      P.v[1][p], P.v[2][p]));
}

}  // namespace talus
