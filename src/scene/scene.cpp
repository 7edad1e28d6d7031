#include "talus/scene/scene.hpp"

#include "talus/particles/cell_sort.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/shape/bspline.hpp"
#include "talus/shape/gimp.hpp"
#include "talus/shape/linear.hpp"

#include "body_label.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace talus {

ShapeReach shape_reach(ShapeKind shape) {
  switch (shape) {
    case ShapeKind::Linear: return {LinearShape::kReachLow, LinearShape::kReachHigh};
    case ShapeKind::UGimp: return {UGimpShape::kReachLow, UGimpShape::kReachHigh};
    case ShapeKind::CpGimp: return {CpGimpShape::kReachLow, CpGimpShape::kReachHigh};
    case ShapeKind::BSpline2: return {QuadraticBSplineShape::kReachLow, QuadraticBSplineShape::kReachHigh};
  }
  return {LinearShape::kReachLow, LinearShape::kReachHigh};
}

int colour_block_edge(const Scene& scene) {
  const ShapeReach reach = shape_reach(scene.shape);
  return CellSort::block_edge(reach.low, reach.high, scene.block_cells);
}

double Scene::initial_time_step() const {
  double max_rate = 0.0;
  for (const BodySpec& body : bodies) max_rate = std::max(max_rate, wave_speed(body) + body.velocity.norm());
  return courant * grid.h / max_rate;
}

double Scene::wave_speed(const BodySpec& body) const {
  const MaterialSpec& m = materials[body.material];
  return std::sqrt(m.elastic.p_wave() / m.density);
}

const char* to_string(SchemeKind scheme) {
  switch (scheme) {
    case SchemeKind::Musl: return "musl";
    case SchemeKind::Usl: return "usl";
    case SchemeKind::Usf: return "usf";
    case SchemeKind::Usavg: return "usavg";
  }
  return "?";
}

const char* to_string(ScatterOrder order) {
  switch (order) {
    case ScatterOrder::ColourPasses: return "colour_passes";
    case ScatterOrder::BlockBuffers: return "block_buffers";
  }
  return "?";
}

const char* to_string(ShapeKind shape) {
  switch (shape) {
    case ShapeKind::Linear: return "linear";
    case ShapeKind::UGimp: return "ugimp";
    case ShapeKind::CpGimp: return "cpgimp";
    case ShapeKind::BSpline2: return "bspline2";
  }
  return "?";
}

const char* to_string(MaterialModel model) {
  switch (model) {
    case MaterialModel::LinearElastic: return "linear_elastic";
    case MaterialModel::DruckerPrager: return "drucker_prager";
    case MaterialModel::MuI: return "mu_i";
  }
  return "?";
}

const char* to_string(ConeFit cone) {
  switch (cone) {
    case ConeFit::PlaneStrain: return "plane_strain";
    case ConeFit::Compression: return "compression";
    case ConeFit::Extension: return "extension";
    case ConeFit::Inscribed: return "inscribed";
  }
  return "?";
}

// How seeding names a body in its errors: its key path, bodies[i] or bodies[i].prism.
BodyLabel body_label(const Scene& scene) {
  return [&scene](std::size_t b) {
    const BodySpec& body = scene.bodies[b];
    return fmt::format("bodies[{}]{}", b, body.shape == BodyShapeKind::Box ? "" : std::string(".") + to_string(body.shape));
  };
}

ParticleStore seed_particles(const Scene& scene, const SeedFilter& keep) {
  std::vector<double> densities;
  for (const MaterialSpec& m : scene.materials) densities.push_back(m.density);
  return seed_particles(scene.grid, scene.bodies, densities, body_label(scene), keep);
}

std::vector<std::int64_t> particles_per_x_cell(const Scene& scene) {
  return particles_per_x_cell(scene.grid, scene.bodies, body_label(scene));
}

std::size_t count_particles(const Scene& scene) { return count_particles(scene.grid, scene.bodies, body_label(scene)); }

}  // namespace talus
