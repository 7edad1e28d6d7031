#pragma once
// Instability guards (docs/reliability.md). Each throws an instability Error (exit code 3) whose
// message is one line: step, time, particle id and body, the field and its value.
//
//  - check_step_displacement (Solver::step, in a step G2P flagged): no particle moved more than
//    guards.max_step_displacement cells in the step (a CFL breach: the Courant condition
//    c dt / h < 1 no longer holds for that particle). G2P itself stops at a non-finite velocity or
//    displacement in the step it appears.
//  - check_particle_fields (Solver::step every kFieldCheckInterval steps, and before the run driver
//    keeps a last good state): every per-particle double array finite
//    (ParticleStore::for_each_double_array, so new arrays are covered) and volumes positive.
//    A non-finite stress or grid value reaches the velocities through P2G/G2P within a step and
//    stops the run there; the scan catches the fields the step never reads (strain, plastic state).
//  - EnergyGuard (called by the run driver whenever it computes the energy budget): the total
//    energy may not grow by more than guards.energy_growth_factor times the energy available.
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"
#include "talus/solver/solver.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace talus {

/// How an instability's message names the step it happened in: `step` steps were done at `time`
/// when it began, so it is step `step` + 1, as the progress line counts ("in step 1, from t = 0 s"
/// for the first; it read "step 0, t = 0 s", and the energy guard, which checks after a step,
/// named that step one higher than the other guards did).
std::string step_started(std::int64_t step, double time);
/// The state after `step` steps, at `time`: "after step 34, t = 0.012 s" (the energy guard's check,
/// and the last good state a run falls back to).
std::string step_ended(std::int64_t step, double time);

/// Every per-particle double array finite and every volume positive. `step` and `time` are those
/// at the start of the step just taken (as in the solver's messages). It reads every particle
/// field (about 200 B per particle), so Solver::step runs it every kFieldCheckInterval steps, and
/// Solver::check_particles() runs it on demand (the run driver, before it keeps a last good state).
void check_particle_fields(const ParticleStore& particles, const Scene& scene, std::int64_t step, double time);

/// No particle moved more than guards.max_step_displacement cells in the step (CFL breach). G2P
/// flags a breach while it computes the displacements; the solver calls this only then, to name
/// the particle.
void check_step_displacement(const ParticleStore& particles, const std::array<std::span<double>, 3>& displacement,
                             const Scene& scene, std::int64_t step, double time);

/// Energy growth: with E the total of EnergyBudget (kinetic + strain + gravity + friction work +
/// plastic work, conserved by the continuum), the run stops when
///     E(t) - E(0) > energy_growth_factor * A(t),
///     A(t) = kinetic(0) + strain(0) + max(0, max over s <= t of gravity(0) - gravity(s)) + M |g| h / 1000,
/// i.e. when the scheme created more energy than the factor times all the energy the system ever
/// had to spend (the initial kinetic and strain energy plus the potential energy released so far;
/// the last term, the work of lifting the whole mass a thousandth of a cell, keeps A positive for
/// a body that starts at rest). While gravity ramps, the potential it withheld (gravity_ramp) is
/// not counted as released: gravity(s) there stands for gravity(s) + gravity_ramp(s).
/// The fastest particle, which the energy guard names as the likeliest seat of an instability (over
/// every rank in a distributed run: Solver::fastest_particle).
struct FastestParticle {
  double speed2 = -1.0;  // |v|^2 (NaN first: a particle whose velocity is not finite)
  std::int64_t id = -1;
  std::int32_t body = -1;
  double x[3] = {0.0, 0.0, 0.0}, v[3] = {0.0, 0.0, 0.0};
  /// The fastest of `particles` (none: id -1).
  static FastestParticle of(const ParticleStore& particles);
  /// Whether this one goes before `other`: a NaN speed first, then the faster, then the lower id.
  bool before(const FastestParticle& other) const;
  /// How the energy guard's stop and warning name it: `particle 23 (body "block")` ("?" without a body).
  std::string label(const Scene& scene) const;
};

/// Where the total energy first grew by more than guards.energy_warning_factor times the energy
/// available (the run warns of it once; run.json's end.energy_growth_warning; kept in checkpoints).
struct EnergyWarning {
  std::int64_t step = 0;
  double time = 0.0;
  double share = 0.0;  // the growth then, of the energy available
};

class EnergyGuard {
 public:
  EnergyGuard() = default;
  /// `mass`: the run's whole mass, every rank's and what left through open faces (the floor of A is
  /// the same whatever the rank count, and the same after a restart as before).
  EnergyGuard(const Scene& scene, double mass, const EnergyBudget& initial);
  /// Throws when the budget `e` breaks the bound, naming the fastest of `particles`; otherwise
  /// records the released potential energy. `step` and `time`: those after the step that gave `e`.
  /// `outflow_gravity`: Solver::outflow_gravity(), the potential the particles that left carried out
  /// (the released energy counts them down to where they left; without it a leaving particle's -m g.x,
  /// which depends on the origin, counted as released or spent).
  void check(const EnergyBudget& e, const ParticleStore& particles, const Scene& scene, std::int64_t step, double time,
             double outflow_gravity = 0.0);
  /// check() in two parts, for a distributed run whose ranks each hold the same ledger: whether `e`
  /// breaks the bound (recording the released energy as check() does), and the error that names
  /// `fastest`.
  bool breached(const EnergyBudget& e, double outflow_gravity);
  [[noreturn]] void fail(const EnergyBudget& e, const FastestParticle& fastest, const Scene& scene, std::int64_t step,
                         double time) const;
  double available() const;
  /// How much the total energy grew since the start, as a share of available(): what both factors
  /// (guards.energy_growth_factor, guards.energy_warning_factor) are compared with.
  double growth_share(const EnergyBudget& e) const { return (e.total() - initial_.total()) / available(); }
  /// Guard state to checkpoint: the most potential energy released so far.
  double max_released() const { return max_released_; }
  void set_max_released(double r) { max_released_ = r; }

 private:
  EnergyBudget initial_;
  double floor_ = 0.0;
  double max_released_ = 0.0;
  double factor_ = 1.0;
};

}  // namespace talus
