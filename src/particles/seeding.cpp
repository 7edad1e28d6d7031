#include "talus/particles/seeding.hpp"

#include "talus/core/error.hpp"

#include <fmt/core.h>

#include <cmath>

namespace talus {

namespace {

/// The particle coordinates along one axis: cell-local points (k + 1/2) h / n inside [lo, hi).
std::vector<double> axis_points(double origin, double h, int n, double lo, double hi) {
  std::vector<double> points;
  const double spacing = h / n;
  const long long first_cell = static_cast<long long>(std::floor((lo - origin) / h)) - 1;
  const long long last_cell = static_cast<long long>(std::ceil((hi - origin) / h)) + 1;
  for (long long c = first_cell; c <= last_cell; ++c)
    for (int k = 0; k < n; ++k) {
      const double p = origin + c * h + (k + 0.5) * spacing;
      if (p >= lo && p < hi) points.push_back(p);
    }
  return points;
}

}  // namespace

ParticleStore seed_particles(const Scene& scene) {
  ParticleStore store;
  const double h = scene.grid.h;
  std::int64_t next_id = 0;
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    const BodySpec& body = scene.bodies[b];
    const MaterialSpec& material = scene.materials[body.material];
    const int n = body.particles_per_cell;
    std::array<std::vector<double>, 3> axes;
    for (int d = 0; d < 3; ++d)
      axes[d] = axis_points(scene.grid.origin[d], h, n, body.box_min[d], body.box_max[d]);
    if (axes[0].empty() || axes[1].empty() || axes[2].empty())
      throw input_error(fmt::format(
          "bodies[{}] (\"{}\") holds no particle: its box is thinner than the particle spacing h/n = {} "
          "along some axis", b, body.name, h / n));
    const double volume = std::pow(h / n, 3);
    const double mass = material.density * volume;
    for (double px : axes[0])
      for (double py : axes[1])
        for (double pz : axes[2])
          store.add(next_id++, Vec3(px, py, pz), body.velocity, mass, volume, static_cast<std::uint16_t>(b));
  }
  return store;
}

}  // namespace talus
