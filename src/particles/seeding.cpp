#include "talus/particles/seeding.hpp"

#include "talus/core/error.hpp"
#include "talus/particles/body_shape.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>

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

/// The candidate points of one body and the test that keeps them. Off a terrain grid the candidates
/// are the cell-local points of the body's bounding box, and the third axis is z. On a terrain grid
/// they are the cell-local points of the (x, y, w) cells of the grid, mapped to z = w + z_b(x) (z_b:
/// the grid's bed, terrain.hpp); the map has unit Jacobian, so each still carries the volume
/// (h/n)^3. A physical body keeps the points inside it: the bed clips a body that reaches below it
/// (candidates exist only in the grid's w column; the scene warns, seeding_warnings), a body with no
/// point in the column is an input error, and so is one with a point above the grid's top.
/// A terrain-frame box reads its third coordinate as w directly. The y range of the candidates is
/// the body's, so the test does not depend on y: counting can multiply by the number of ys.
class BodyCandidates {
 public:
  BodyCandidates(const GridGeometry& grid, const BodySpec& body, std::string label, const ProfileTerrain& bed)
      : grid_(grid), label_(std::move(label)), body_(body), bed_(bed), terrain_(grid.has_terrain()) {
    const GridGeometry& g = grid;
    const int n = body_.particles_per_cell;
    xs_ = axis_points(g.origin[0], g.h, n, body_.box_min[0], body_.box_max[0]);
    ys_ = axis_points(g.origin[1], g.h, n, body_.box_min[1], body_.box_max[1]);
    w_top_ = g.origin[2] + g.cells[2] * g.h;
    // On a terrain grid: every point of the grid's w column.
    third_ = terrain_ ? axis_points(g.origin[2], g.h, n, g.origin[2], w_top_)
                      : axis_points(g.origin[2], g.h, n, body_.box_min[2], body_.box_max[2]);
  }

  /// The points the body holds in the plane of the first y (the test does not depend on y).
  std::size_t points_in_first_plane() const {
    std::size_t in_xz = 0;
    if (!ys_.empty())
      for (double px : xs_) {
        const double zb = terrain_ ? bed_.height(px) : 0.0;
        for (double third : third_) in_xz += inside(px, ys_.front(), third, zb);
      }
    return in_xz;
  }

  /// The points of a physical body on a terrain grid that lie outside the grid's w column, in the
  /// plane of the first y (the test does not depend on y): below its bottom (the bed clips them)
  /// and whether any lies above its top. Zero for other bodies. Only the body's own w range at each
  /// x is walked (walking from the body to the grid took minutes for a body 1e4 m off the bed).
  struct OutsideColumn {
    std::size_t below = 0, above = 0;
  };
  OutsideColumn outside_column() const {
    OutsideColumn out;
    if (!terrain_ || body_.frame == BoxFrame::Terrain || ys_.empty()) return out;
    const GridGeometry& g = grid_;
    for (double px : xs_) {
      const double zb = bed_.height(px);
      const double w_lo = body_.box_min[2] - zb, w_hi = body_.box_max[2] - zb;
      out.below += points_inside(px, zb, w_lo, std::min(w_hi, g.origin[2]), false);
      if (out.above == 0) out.above = points_inside(px, zb, std::max(w_lo, w_top_), w_hi, true);
    }
    return out;
  }

  /// The body's seed points at x = px (first y) with w in [lo, hi); with `any`, 1 as soon as one is
  /// found. A range of more than kMaxWalked points (a body reaching absurdly far outside the grid)
  /// is not walked: its lattice count is returned, exact for a box, an upper bound for a prism.
  std::size_t points_inside(double px, double zb, double lo, double hi, bool any) const {
    if (!(hi > lo)) return 0;
    constexpr double kMaxWalked = 1e6;
    const double lattice = (hi - lo) / (grid_.h / body_.particles_per_cell);
    if (lattice > kMaxWalked) return any ? 1 : static_cast<std::size_t>(lattice);
    std::size_t count = 0;
    for (double w : axis_points(grid_.origin[2], grid_.h, body_.particles_per_cell, lo, hi))
      if (inside(px, ys_.front(), w, zb) && (++count, any)) break;
    return count;
  }

  /// Visit every kept point in seeding order (x, then y, then the third axis): f(Vec3 position).
  template <class F>
  void for_each_point(F&& f) const {
    for (double px : xs_) {
      const double zb = terrain_ ? bed_.height(px) : 0.0;
      for (double py : ys_)
        for (double third : third_)
          if (inside(px, py, third, zb)) f(Vec3(px, py, terrain_ ? third + zb : third));
    }
  }

  /// The points of this body that `other` holds as well, which seeding makes twice (each body seeds
  /// its own), and the box around them (particle positions). Both bodies are extrusions along y, so
  /// one plane of y that both hold settles it in the x-z plane; the count is that plane's times this
  /// body's planes of y inside the other's range.
  struct SharedPoints {
    std::size_t count = 0;
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  };
  SharedPoints points_also_in(const BodyCandidates& other) const {
    SharedPoints shared;
    std::size_t shared_ys = 0;
    for (double y : ys_)
      if (y >= other.body_.box_min[1] && y < other.body_.box_max[1]) {
        ++shared_ys;
        shared.lo[1] = std::min(shared.lo[1], y);
        shared.hi[1] = std::max(shared.hi[1], y);
      }
    if (shared_ys == 0) return {};
    for (double px : xs_) {
      if (px < other.body_.box_min[0] || px >= other.body_.box_max[0]) continue;
      const double zb = terrain_ ? bed_.height(px) : 0.0;
      for (double third : third_) {
        const Vec3 point(px, shared.lo[1], terrain_ ? third + zb : third);
        if (!inside(px, point[1], third, zb) || !other.holds(point)) continue;
        shared.count += shared_ys;
        for (int d : {0, 2}) {
          shared.lo[d] = std::min(shared.lo[d], point[d]);
          shared.hi[d] = std::max(shared.hi[d], point[d]);
        }
      }
    }
    return shared.count > 0 ? shared : SharedPoints{};
  }

  /// The number of points the body holds. Throws the input errors of a body that reaches above a
  /// terrain grid or holds no particle, naming the body by its label.
  std::size_t count() const {
    const std::size_t in_xz = points_in_first_plane();
    const double spacing = grid_.h / body_.particles_per_cell;
    const bool box = body_.shape == BodyShapeKind::Box;
    const OutsideColumn outside = outside_column();
    if (outside.above > 0)
      throw input_error(fmt::format(
          "{} (\"{}\") reaches above the grid's top (w = {:.6g} above the bed: grid.origin[2] + grid.size[2] with "
          "grid.terrain) over {} its x range",
          label_, body_.name, w_top_, in_xz == 0 && outside.below == 0 ? "all of" : "part of"));
    if (terrain_ && in_xz == 0)
      throw input_error(fmt::format(
          "{} (\"{}\") holds no particle: {}",
          label_, body_.name, outside.below > 0
              ? "it lies below the bed (grid.terrain; the body's z is physical, the bed's height at x is z_b(x))"
              : fmt::format("it is thinner than the particle spacing h/n = {}", spacing)));
    if (xs_.empty() || ys_.empty() || third_.empty())
      throw input_error(fmt::format(
          "{} (\"{}\") holds no particle: its {} is thinner than the particle spacing h/n = {} "
          "along some axis", label_, body_.name, box ? "box" : "bounding box", spacing));
    if (in_xz == 0)
      throw input_error(fmt::format("{} (\"{}\") holds no particle: no particle point (spacing h/n = {}) "
                                    "lies inside it", label_, body_.name, spacing));
    return in_xz * ys_.size();
  }

 private:
  /// Whether the body would keep a point at the physical position p (x, y and z), were it one of its
  /// candidates: the test below, with the ranges the candidates' lattice stands for.
  bool holds(const Vec3& p) const {
    if (!terrain_) return body_contains(body_, p);
    const double w = p[2] - bed_.height(p[0]);
    if (w < grid_.origin[2] || w >= w_top_) return false;  // outside the grid's w column: never seeded
    if (body_.frame != BoxFrame::Terrain) return body_contains(body_, p);
    return body_contains(body_, Vec3(p[0], p[1], w));  // a terrain-frame box reads its third axis as w
  }

  // Whether a candidate lies in the body (the box's x and y ranges are those of xs and ys): a
  // terrain-frame box by its w range, a box off a terrain grid always, any other body by its own
  // inside test at (x, y, z).
  bool inside(double px, double py, double third, double zb) const {
    if (!terrain_) return body_.shape == BodyShapeKind::Box || body_contains(body_, Vec3(px, py, third));
    if (body_.frame == BoxFrame::Terrain) return third >= body_.box_min[2] && third < body_.box_max[2];
    return body_contains(body_, Vec3(px, py, third + zb));
  }

  const GridGeometry& grid_;
  std::string label_;
  const BodySpec& body_;
  const ProfileTerrain& bed_;
  bool terrain_;
  double w_top_ = 0.0;
  std::vector<double> xs_, ys_, third_;
};


std::string name_of(const BodyLabel& label, std::size_t b) { return label ? label(b) : fmt::format("body {}", b); }

}  // namespace

std::size_t count_particles(const GridGeometry& grid, const std::vector<BodySpec>& bodies, const BodyLabel& label) {
  const ProfileTerrain bed = grid_bed(grid);
  std::size_t total = 0;
  for (std::size_t b = 0; b < bodies.size(); ++b) total += BodyCandidates(grid, bodies[b], name_of(label, b), bed).count();
  return total;
}

ParticleStore seed_particles(const GridGeometry& grid, const std::vector<BodySpec>& bodies,
                             const std::vector<double>& material_density, const BodyLabel& label,
                             const SeedFilter& keep) {
  ParticleStore store;
  // exact: no array grows past its final size while seeding (a slab's share is not known in advance)
  const std::size_t total = count_particles(grid, bodies, label);
  if (!keep) store.reserve(total);
  const ProfileTerrain bed = grid_bed(grid);
  std::int64_t next_id = 0;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const BodySpec& body = bodies[b];
    const double volume = std::pow(grid.h / body.particles_per_cell, 3);
    const double mass = material_density.at(body.material) * volume;
    BodyCandidates(grid, body, name_of(label, b), bed).for_each_point([&](const Vec3& position) {
      const std::int64_t id = next_id++;
      if (!keep || keep(position)) store.add(id, position, body.velocity, mass, volume, static_cast<std::uint16_t>(b));
    });
  }
  return store;
}

std::vector<std::string> seeding_warnings(const GridGeometry& grid, const std::vector<BodySpec>& bodies,
                                          const BodyLabel& label) {
  std::vector<std::string> warnings;
  const ProfileTerrain bed = grid_bed(grid);
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const BodyCandidates candidates(grid, bodies[b], name_of(label, b), bed);
    const std::size_t below = candidates.outside_column().below, kept = candidates.points_in_first_plane();
    // A body wholly below the bed is an input error (count_particles): only a partial clip warns.
    if (below > 0 && kept > 0)
      warnings.push_back(fmt::format(
          "{} (\"{}\") reaches below the bed (grid.terrain) over part of its x range: the bed clips it, {:.3g}% of "
          "its particles are not seeded (raise it, or seed a layer on the bed with box.frame = \"terrain\")",
          name_of(label, b), bodies[b].name, 100.0 * below / (below + kept)));
  }
  // Two bodies that share a volume both seed it: twice the mass there, and with the same particles
  // per cell the particles sit on top of each other. Any shapes and frames (a prism over a box, a
  // physical box over a terrain-frame one were not checked before 2026-12-07).
  for (std::size_t a = 0; a < bodies.size(); ++a)
    for (std::size_t b = a + 1; b < bodies.size(); ++b) {
      const BodyCandidates first(grid, bodies[a], name_of(label, a), bed), second(grid, bodies[b], name_of(label, b), bed);
      const auto shared = first.points_also_in(second);
      if (shared.count == 0) continue;
      warnings.push_back(fmt::format(
          "{} (\"{}\") and {} (\"{}\") overlap: {} of the {} particles of {} (in [{:.6g}, {:.6g}, {:.6g}] - "
          "[{:.6g}, {:.6g}, {:.6g}]) lie inside {} as well, and both seed particles there (twice the mass)",
          name_of(label, a), bodies[a].name, name_of(label, b), bodies[b].name, shared.count, first.count(),
          name_of(label, a), shared.lo[0], shared.lo[1], shared.lo[2], shared.hi[0], shared.hi[1], shared.hi[2],
          name_of(label, b)));
    }
  return warnings;
}

std::vector<std::int64_t> particles_per_x_cell(const GridGeometry& grid, const std::vector<BodySpec>& bodies,
                                               const BodyLabel& label) {
  count_particles(grid, bodies, label);  // the same input errors as seeding
  const ProfileTerrain bed = grid_bed(grid);
  const int cells = grid.cells[0] + 2 * kPad;
  std::vector<std::int64_t> counts(cells, 0);
  for (std::size_t b = 0; b < bodies.size(); ++b)
    BodyCandidates(grid, bodies[b], name_of(label, b), bed).for_each_point([&](const Vec3& position) {
      ++counts[std::clamp(grid.cell_of(0, position[0]), 0, cells - 1)];
    });
  return counts;
}

}  // namespace talus
