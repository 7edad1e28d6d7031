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

/// A body on a terrain grid. Candidate points are the cell-local points of the (x, y, w) cells of the
/// grid, mapped to z = w + z_b(x) (z_b: the grid's bed, terrain.hpp); the map has unit Jacobian, so
/// each still carries the volume (h/n)^3. A physical box keeps the points inside it: the bed clips a
/// box that reaches below it (candidates exist only above the bed), and a box with no point above
/// the bed is an input error. A terrain-frame box reads its third coordinate as w directly.
void seed_on_terrain(const GridGeometry& g, const BodySpec& body, std::size_t b, const std::string& label,
                     double density, const ProfileTerrain& bed, ParticleStore& store, std::int64_t& next_id) {
  const double h = g.h;
  const int n = body.particles_per_cell;
  const double w_top = g.origin[2] + g.cells[2] * h;
  const std::vector<double> xs = axis_points(g.origin[0], h, n, body.box_min[0], body.box_max[0]);
  const std::vector<double> ys = axis_points(g.origin[1], h, n, body.box_min[1], body.box_max[1]);
  // every point of the grid's w column, and one cell of points above the top: a body that holds
  // one of those reaches above the grid
  const std::vector<double> ws = axis_points(g.origin[2], h, n, g.origin[2], w_top + h);
  const double volume = std::pow(h / n, 3);
  const double mass = density * volume;
  const bool terrain_frame = body.frame == BoxFrame::Terrain;
  // Whether a candidate lies in the body (the box's x and y ranges are those of xs and ys): a
  // terrain-frame box by its w range, any physical body by its own inside test at (x, y, z).
  const auto inside = [&](double px, double py, double pw, double pz) {
    if (terrain_frame) return pw >= body.box_min[2] && pw < body.box_max[2];
    return body_contains(body, Vec3(px, py, pz));
  };
  const std::size_t first = store.size();
  bool above_top = false;
  for (double px : xs) {
    const double zb = bed.height(px);
    for (double py : ys)
      for (double pw : ws) {
        const double pz = pw + zb;
        if (!inside(px, py, pw, pz)) continue;
        if (pw >= w_top) {
          above_top = true;
          continue;
        }
        store.add(next_id++, Vec3(px, py, pz), body.velocity, mass, volume, static_cast<std::uint16_t>(b));
      }
  }
  if (above_top)
    throw input_error(fmt::format(
        "{} (\"{}\") reaches above the grid's top (w = {} above the bed: grid.origin[2] + grid.size[2] with "
        "grid.terrain) over part of its x range",
        label, body.name, w_top));
  if (store.size() == first)
    throw input_error(fmt::format(
        "{} (\"{}\") holds no particle: it lies below the bed (grid.terrain) or is thinner than the "
        "particle spacing h/n = {}",
        label, body.name, h / n));
}

}  // namespace

ParticleStore seed_particles(const GridGeometry& grid, const std::vector<BodySpec>& bodies,
                             const std::vector<double>& material_density, const BodyLabel& label) {
  ParticleStore store;
  const double h = grid.h;
  std::int64_t next_id = 0;
  const ProfileTerrain bed = grid_bed(grid);
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const BodySpec& body = bodies[b];
    const double density = material_density.at(body.material);
    const int n = body.particles_per_cell;
    const std::string name = label ? label(b) : fmt::format("body {}", b);
    if (grid.has_terrain()) {
      seed_on_terrain(grid, body, b, name, density, bed, store, next_id);
      continue;
    }
    std::array<std::vector<double>, 3> axes;
    for (int d = 0; d < 3; ++d)
      axes[d] = axis_points(grid.origin[d], h, n, body.box_min[d], body.box_max[d]);
    const bool box = body.shape == BodyShapeKind::Box;
    if (axes[0].empty() || axes[1].empty() || axes[2].empty())
      throw input_error(fmt::format(
          "{} (\"{}\") holds no particle: its {} is thinner than the particle spacing h/n = {} "
          "along some axis", name, body.name, box ? "box" : "bounding box", h / n));
    const double volume = std::pow(h / n, 3);
    const double mass = density * volume;
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
                                    "lies inside it", name, body.name, h / n));
  }
  return store;
}

}  // namespace talus
