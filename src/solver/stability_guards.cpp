#include "talus/solver/stability_guards.hpp"
#include "talus/solver/dilation_check.hpp"

#include "talus/core/error.hpp"

#include <fmt/core.h>
#include <span>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace talus {

std::string step_started(std::int64_t step, double time) {
  return fmt::format("in step {}, from t = {:.6g} s", step + 1, time);
}

std::string step_ended(std::int64_t step, double time) { return fmt::format("after step {}, t = {:.6g} s", step, time); }

namespace {

std::string labelled(std::int64_t id, std::int64_t body, const Scene& scene) {
  const bool named = body >= 0 && static_cast<std::size_t>(body) < scene.bodies.size();
  return fmt::format("particle {} (body \"{}\")", id, named ? scene.bodies[static_cast<std::size_t>(body)].name : "?");
}

std::string particle_label(const ParticleStore& P, const Scene& scene, std::size_t p) {
  return labelled(P.id[p], P.body[p], scene);
}

std::string where(const ParticleStore& P, std::size_t p) {
  return fmt::format("position ({:.6g}, {:.6g}, {:.6g}) m, velocity ({:.6g}, {:.6g}, {:.6g}) m/s", P.x[0][p], P.x[1][p],
                     P.x[2][p], P.v[0][p], P.v[1][p], P.v[2][p]);
}

}  // namespace

namespace {

// V/V0 beyond which a particle counts as dilated without bound, per body: kDilationWarningRatio for the
// granular bodies whose separation rule is off; infinity for the rest (never passed).
std::vector<double> dilation_bounds(const Scene& scene) {
  std::vector<double> bound(scene.bodies.size(), std::numeric_limits<double>::infinity());
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    const MaterialSpec& m = scene.materials[scene.bodies[b].material];
    const bool granular = m.model == MaterialModel::DruckerPrager || m.model == MaterialModel::MuI;
    if (granular && !(m.granular.separation_volume_ratio > 0.0)) bound[b] = kDilationWarningRatio;
  }
  return bound;
}

std::string dilation_line(const ParticleStore& P, const Scene& scene, std::size_t p, double ratio, double seeded,
                          std::int64_t step, double time) {
  const MaterialSpec& m = scene.materials[scene.bodies[static_cast<std::size_t>(P.body[p])].material];
  return fmt::format(
      "{}: {} has dilated to {:.3g} times its seeded volume (density {:.3g} kg/m³, seeded at {:.6g}) with "
      "materials.{}.separation_volume_ratio = 0 (off): nothing bounds a granular particle's dilation then, and its "
      "falling wave speed and growing volume shrink the time step; a separation_volume_ratio (default 1.5) sets such "
      "particles stress-free (docs/drucker-prager.md §7b)",
      step_started(step, time), particle_label(P, scene, p), ratio, P.mass[p] / P.volume[p], seeded, m.name);
}

// check_particle_fields, and with `dilation` the first dilated particle's line (dilation_bounds).
std::string scan_particle_fields(const ParticleStore& P, const Scene& scene, std::int64_t step, double time,
                                 bool dilation) {
  const std::size_t n = P.size();
  // Finite values: x * 0 is NaN exactly when x is NaN or Inf; the slow search for the first bad
  // particle runs only when a scan fails. One parallel region scans every array in use and the volume
  // (a region per array was a fork/join each, a serial part at many cores); the diagnosis is the same:
  // the first bad array in visit order, its first bad particle, then the volume.
  std::vector<const ParticleArray<double>*> arrays;
  std::vector<const char*> names;
  P.for_each_double_array([&](const char* name, const ParticleArray<double>& a) {
    if (a.size() != n) return;  // arrays the scene does not use are empty
    arrays.push_back(&a);
    names.push_back(name);
  });
  std::vector<unsigned char> bad(arrays.size(), 0);
  // A particle's volume against the one it was seeded with, mass / material density: an impact at
  // 1000 m/s compressed elastic particles to a millionth of their volume (density 1e9 kg/m^3) and the
  // run ended as "done", every field finite and no energy created.
  const double min_ratio = scene.guards.min_volume_ratio;
  std::vector<double> seeded_density(scene.bodies.size());
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) seeded_density[b] = scene.materials[scene.bodies[b].material].density;
  const auto compressed = [&](std::size_t p) { return P.volume[p] * seeded_density[P.body[p]] < min_ratio * P.mass[p]; };
  // and, asked, against kDilationWarningRatio times it where nothing else bounds it (a warning)
  const std::vector<double> dilation_bound =
      dilation ? dilation_bounds(scene) : std::vector<double>(scene.bodies.size(), std::numeric_limits<double>::infinity());
  const auto dilated = [&](std::size_t p) {
    return P.volume[p] * seeded_density[P.body[p]] > dilation_bound[P.body[p]] * P.mass[p];
  };
  int inverted = 0, crushed = 0, loosened = 0;
  // Eight probes, each summing every eighth element: one probe was a chain of dependent additions,
  // an element per addition's latency (the scan took a fifth of a default-flume step); eight
  // independent ones fill a vector register. Any NaN or Inf still makes its probe NaN.
  constexpr std::size_t kProbes = 8;
  const std::size_t groups = (n + kProbes - 1) / kProbes;
#pragma omp parallel reduction(| : inverted, crushed, loosened)
  {
    for (std::size_t a = 0; a < arrays.size(); ++a) {
      const double* data = arrays[a]->data();
      double probe[kProbes] = {};
#pragma omp for schedule(static) nowait
      for (std::size_t g = 0; g < groups; ++g) {
        const std::size_t first = g * kProbes;
        if (first + kProbes <= n) {
          for (std::size_t l = 0; l < kProbes; ++l) probe[l] += data[first + l] * 0.0;
        } else {
          for (std::size_t p = first; p < n; ++p) probe[0] += data[p] * 0.0;
        }
      }
      bool finite = true;
      for (std::size_t l = 0; l < kProbes; ++l) finite = finite && probe[l] == 0.0;
      if (!finite) {
#pragma omp atomic write
        bad[a] = 1;
      }
    }
#pragma omp for schedule(static) nowait
    for (std::size_t p = 0; p < n; ++p) {
      inverted |= P.volume[p] > 0.0 ? 0 : 1;
      crushed |= compressed(p) ? 1 : 0;
      loosened |= dilated(p) ? 1 : 0;
    }
  }
  for (std::size_t a = 0; a < arrays.size(); ++a) {
    if (!bad[a]) continue;
    const double* data = arrays[a]->data();
    for (std::size_t p = 0; p < n; ++p)
      if (!std::isfinite(data[p]))
        throw instability_error(fmt::format("{}: {} field {} = {} is not finite; {}", step_started(step, time),
                                            particle_label(P, scene, p), names[a], data[p], where(P, p)));
  }
  if (inverted)
    for (std::size_t p = 0; p < n; ++p)
      if (!(P.volume[p] > 0.0))
        throw instability_error(fmt::format("{}: {} field volume = {:.6g} m^3 is not positive "
                                            "(particle inverted); {}",
                                            step_started(step, time), particle_label(P, scene, p), P.volume[p], where(P, p)));
  if (crushed)
    for (std::size_t p = 0; p < n; ++p)
      if (compressed(p)) {
        const double ratio = P.volume[p] * seeded_density[P.body[p]] / P.mass[p];
        throw instability_error(fmt::format(
            "{}: {} field volume = {:.6g} m^3 is {:.6g} of its seeded volume, below "
            "guards.min_volume_ratio = {} (density {:.3g} kg/m^3); {}",
            step_started(step, time), particle_label(P, scene, p), P.volume[p], ratio, min_ratio, P.mass[p] / P.volume[p], where(P, p)));
      }
  if (loosened)
    for (std::size_t p = 0; p < n; ++p)
      if (dilated(p)) {
        const double seeded = seeded_density[P.body[p]];
        return dilation_line(P, scene, p, P.volume[p] * seeded / P.mass[p], seeded, step, time);
      }
  return {};
}

}  // namespace

void check_particle_fields(const ParticleStore& P, const Scene& scene, std::int64_t step, double time) {
  scan_particle_fields(P, scene, step, time, false);
}

std::string check_particle_fields_and_dilation(const ParticleStore& P, const Scene& scene, std::int64_t step,
                                               double time) {
  return scan_particle_fields(P, scene, step, time, true);
}

void check_step_displacement(const ParticleStore& P, const std::array<std::span<double>, 3>& displacement,
                             const Scene& scene, std::int64_t step, double time) {
  const std::size_t n = P.size();
  const double h = scene.grid.h;
  const double limit = scene.guards.max_step_displacement * h;
  const double limit2 = limit * limit;
  if (displacement[0].size() != n) return;
  // Called when G2P flagged a displacement beyond the limit (GatherResult::large_displacement):
  // find the first such particle and name it.
  for (std::size_t p = 0; p < n; ++p) {
    const double d2 = displacement[0][p] * displacement[0][p] + displacement[1][p] * displacement[1][p] +
                      displacement[2][p] * displacement[2][p];
    if (d2 > limit2) {
      const double d = std::sqrt(d2);
      throw instability_error(fmt::format(
            "{}: {} field displacement = {:.6g} m in one step, {:.6g} cells > "
            "guards.max_step_displacement = {} (CFL breach); {}",
            step_started(step, time), particle_label(P, scene, p), d, d / h, scene.guards.max_step_displacement, where(P, p)));
    }
  }
}

EnergyGuard::EnergyGuard(const Scene& scene, double mass, const EnergyBudget& initial)
    : initial_(initial), factor_(scene.guards.energy_growth_factor) {
  floor_ = 1e-3 * mass * scene.gravity.norm() * scene.grid.h;
}

FastestParticle FastestParticle::of(const ParticleStore& P) {
  FastestParticle fastest;
  for (std::size_t p = 0; p < P.size(); ++p) {
    FastestParticle candidate;
    candidate.speed2 = P.v[0][p] * P.v[0][p] + P.v[1][p] * P.v[1][p] + P.v[2][p] * P.v[2][p];
    candidate.id = P.id[p];
    if (!candidate.before(fastest)) continue;  // (none yet: speed2 -1, which any particle is before)
    candidate.body = P.body[p];
    for (int d = 0; d < 3; ++d) {
      candidate.x[d] = P.x[d][p];
      candidate.v[d] = P.v[d][p];
    }
    fastest = candidate;
  }
  return fastest;
}

std::string FastestParticle::label(const Scene& scene) const { return labelled(id, body, scene); }

bool FastestParticle::before(const FastestParticle& other) const {
  if (std::isnan(speed2) != std::isnan(other.speed2)) return std::isnan(speed2);
  if (speed2 != other.speed2 && !std::isnan(speed2)) return speed2 > other.speed2;
  return id < other.id;
}

double EnergyGuard::available() const {
  const double a = initial_.kinetic + initial_.strain + max_released_ + floor_;
  // Round-off of the total itself (gravity is measured from the grid origin, so it can be large).
  const double roundoff = 1e-12 * (std::abs(initial_.gravity) + std::abs(initial_.total()));
  return std::max(a, roundoff) + 1e-300;
}

bool EnergyGuard::breached(const EnergyBudget& e, double outflow_gravity) {
  // (less what a gravity ramp withheld, EnergyBudget::gravity_ramp: that part did no work)
  const double released = initial_.gravity - (e.gravity + outflow_gravity) - (e.gravity_ramp - initial_.gravity_ramp);
  if (std::isfinite(released) && released > max_released_) max_released_ = released;
  const double growth = e.total() - initial_.total();
  return !(std::isfinite(growth) && growth <= factor_ * available());
}

void EnergyGuard::fail(const EnergyBudget& e, const FastestParticle& fastest, const Scene& scene, std::int64_t step,
                       double time) const {
  // The fastest particle is the likeliest seat of the instability: name it.
  throw instability_error(fmt::format(
      "{}: total energy = {:.6g} J grew by {:.6g} J, more than guards.energy_growth_factor = {} times "
      "the energy available ({:.6g} J); fastest: {} field speed = {:.6g} m/s; position ({:.6g}, "
      "{:.6g}, {:.6g}) m, velocity ({:.6g}, {:.6g}, {:.6g}) m/s",
      step_ended(step, time), e.total(), e.total() - initial_.total(), factor_, available(), fastest.label(scene),
      std::sqrt(std::max(fastest.speed2, 0.0)), fastest.x[0], fastest.x[1], fastest.x[2], fastest.v[0], fastest.v[1],
      fastest.v[2]));
}

void EnergyGuard::check(const EnergyBudget& e, const ParticleStore& P, const Scene& scene, std::int64_t step,
                        double time, double outflow_gravity) {
  if (breached(e, outflow_gravity)) fail(e, FastestParticle::of(P), scene, step, time);
}

}  // namespace talus
