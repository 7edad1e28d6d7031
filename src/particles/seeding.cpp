#include "talus/particles/seeding.hpp"

#include "talus/core/error.hpp"
#include "talus/particles/body_shape.hpp"

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
    const bool box = body.shape == BodyShapeKind::Box;
    const std::string key = box ? fmt::format("bodies[{}]", b) : fmt::format("bodies[{}].{}", b, to_string(body.shape));
    if (axes[0].empty() || axes[1].empty() || axes[2].empty())
      throw input_error(fmt::format(
          "{} (\"{}\") holds no particle: its {} is thinner than the particle spacing h/n = {} "
          "along some axis", key, body.name, box ? "box" : "bounding box", h / n));
    const double volume = std::pow(h / n, 3);
    const double mass = material.density * volume;
    const std::int64_t first_id = next_id;
    // The candidates span the bounding box; a box keeps them all, other shapes keep those inside.
    for (double px : axes[0])
      for (double py : axes[1])
        for (double pz : axes[2]) {
          const Vec3 position(px, py, pz);
          if (box || body_contains(body, position))
            store.add(next_id++, position, body.velocity, mass, volume, static_cast<std::uint16_t>(b));
        }
    if (next_id == first_id)
      throw input_error(fmt::format("{} (\"{}\") holds no particle: no particle point (spacing h/n = {}) "
                                    "lies inside it", key, body.name, h / n));
  }
  return store;
}

}  // namespace talus
