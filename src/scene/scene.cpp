#include "talus/scene/scene.hpp"

#include "talus/grid/terrain_profile.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/shape/bspline.hpp"
#include "talus/shape/gimp.hpp"
#include "talus/shape/linear.hpp"

#include "terrain_warnings.hpp"
#include "usage_warnings.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

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

namespace {

// How seeding names a body in its errors: its key path, bodies[i] or bodies[i].prism.
BodyLabel body_label(const Scene& scene) {
  return [&scene](std::size_t b) {
    const BodySpec& body = scene.bodies[b];
    return fmt::format("bodies[{}]{}", b, body.shape == BodyShapeKind::Box ? "" : std::string(".") + to_string(body.shape));
  };
}

// The bodies' footprint along x: the x range over which they rest on the bed (a prism's vertices
// within half a cell of the bed: the flume's wedge rests on [-0.21, 0] while its free surface
// reaches 0.08 m past the gate), or their whole extent along x where nothing rests on it.
std::array<double, 2> bodies_footprint_x(const Scene& scene) {
  const GridGeometry& g = scene.grid;
  std::optional<TerrainProfile> profile;
  if (g.has_terrain()) profile.emplace(g.terrain);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const BodySpec& b : scene.bodies) {
    double b_lo = b.box_min[0], b_hi = b.box_max[0];
    if (b.shape == BodyShapeKind::Prism) {
      double on_lo = std::numeric_limits<double>::infinity(), on_hi = -on_lo;
      for (const auto& p : b.prism.points) {
        const double bed = profile ? profile->height(p[0]) : g.origin[2];
        if (std::abs(p[1] - bed) <= 0.5 * g.h) on_lo = std::min(on_lo, p[0]), on_hi = std::max(on_hi, p[0]);
      }
      if (on_lo <= on_hi) b_lo = on_lo, b_hi = on_hi;
    }
    lo = std::min(lo, b_lo);
    hi = std::max(hi, b_hi);
  }
  return {lo, hi};
}

// A bed that rises along +x under the runout diagnostics, which measure along +x.
void add_runout_direction_warning(const Scene& scene, std::vector<std::string>& warnings) {
  const GridGeometry& grid = scene.grid;
  const double g = scene.gravity.norm();
  // The runout is measured down the flume along +x: the front is the mass quantile of the largest s.
  // A profile surveyed from the toe up (the bed rising along +x) reported the scarp as the "front"
  // while 8.8% of the mass left through x- (a user's run). The test: the bed under the bodies (over
  // their footprint along x) rises along +x, so that they flow toward -x (a valley whose far wall
  // ends higher than the slide starts is not warned about); on a flat grid, gravity pulling along -x.
  if (scene.runout.enabled && !scene.bodies.empty()) {
    if (grid.has_terrain()) {
      const TerrainProfile profile(grid.terrain);
      const auto [lo, hi] = bodies_footprint_x(scene);
      const double z_lo = profile.height(lo), z_hi = profile.height(hi);
      const double slope = hi > lo ? (z_hi - z_lo) / (hi - lo) : profile.slope(lo);
      if (slope > 1e-9)
        warnings.push_back(fmt::format(
            "diagnostics.runout on a bed that rises along +x under the bodies (grid.terrain: z = {:.6g} m at x = "
            "{:.6g} m and {:.6g} m at x = {:.6g} m, the ends of their footprint): the runout is measured down the "
            "flume along +x (the front is the mass's farthest s along +x), so on this bed the front is the upslope "
            "end of the mass; mirror the profile (x -> -x, the points in reverse order) and the bodies so that the "
            "bed descends along +x",
            z_lo, lo, z_hi, hi));
    } else if (scene.gravity[0] < -1e-9 * g) {
      warnings.push_back(fmt::format(
          "diagnostics.runout with gravity[0] = {} < 0 on a flat grid: the flow runs along -x, but the runout is "
          "measured along +x (the front is the mass's farthest x), so the front is the upslope end of the mass; "
          "mirror the scene along x (gravity[0] > 0)",
          scene.gravity[0]));
    }
  }
}

// Values in another unit than the key's, which pass every range (as friction_angle and
// friction_coefficient in scene_warnings), and an elastic modulus too soft to carry the body's weight.
void add_unit_warnings(const Scene& scene, std::vector<std::string>& warnings) {
  const GridGeometry& grid = scene.grid;
  const double g = scene.gravity.norm();
  // Units written wrong pass every range. A scene
  // with gravity of 1 to 50 m/s^2 is in SI units; the benchmarks in inputs/benchmarks/ are not (density 1
  // with gravity 0 or 200-250 m/s^2 along x), and are not warned about.
  constexpr double kLightest = 100.0, kHeaviest = 25000.0;  // kg/m^3: dry snow and up; osmium is 22 600
  constexpr double kGravityLow = 1.0, kGravityHigh = 50.0;  // m/s^2
  const bool si_gravity = g >= kGravityLow && g <= kGravityHigh;
  for (const MaterialSpec& m : scene.materials) {
    if (si_gravity && m.density < kLightest)
      warnings.push_back(fmt::format(
          "materials.{}.density = {} kg/m³ is below {} kg/m³, lighter than any soil or rock: in g/cm³ or t/m³? ({} "
          "g/cm³ is {:.6g} kg/m³)",
          m.name, m.density, kLightest, m.density, m.density * 1000.0));
    if (si_gravity && m.density > kHeaviest)
      warnings.push_back(fmt::format(
          "materials.{}.density = {} kg/m³ is above {} kg/m³, heavier than any rock (osmium: 22 600): a unit weight "
          "ρ g in N/m³ ({:.6g} kg/m³ at |g| = {:.4g} m/s²), or another unit?",
          m.name, m.density, kHeaviest, m.density / g, g));
    // d in I = shear rate d / sqrt(p / rho_s) (docs/mu-i.md): the shipped scenes' 0.5 mm sand and beads.
    constexpr double kCoarsest = 0.05;  // m: coarse gravel; boulders are no μ(I) continuum at these cells
    if (m.model == MaterialModel::MuI && m.mu_i.grain_diameter > kCoarsest)
      warnings.push_back(fmt::format(
          "materials.{}.grain_diameter = {} m is a grain of {:.4g} mm, above {} m: in metres, not millimetres? (0.5 "
          "mm is 0.0005)",
          m.name, m.mu_i.grain_diameter, m.mu_i.grain_diameter * 1000.0, kCoarsest));
  }
  // On a terrain grid the profile tilts the bed: a tilted gravity counts the slope twice.
  if (grid.has_terrain() && g > 0.0) {
    const Vec3& v = scene.gravity;
    if (std::hypot(v[0], v[1]) > 1e-9 * g)
      warnings.push_back(fmt::format(
          "gravity = [{}, {}, {}] on a terrain grid has a component along x or y: grid.terrain already tilts the bed, "
          "so the slope is counted twice; give gravity [0, 0, -{:.4g}] (a tilted gravity is for a flat grid)",
          v[0], v[1], v[2], g));
    if (v[2] > 0.0)
      warnings.push_back(fmt::format(
          "gravity[2] = {} > 0 on a terrain grid points up, away from the bed: z is up; give gravity [0, 0, -{:.4g}]",
          v[2], g));
    if (g < kGravityLow || g > kGravityHigh)
      warnings.push_back(fmt::format(
          "|gravity| = {:.6g} m/s² on a terrain grid is far from 9.81 (outside [{}, {}]): in cm/s² or another unit?",
          g, kGravityLow, kGravityHigh));
  }
  // Self-weight: a body of height H under its own weight strains by about rho g H / E. Above 0.1 the
  // small-strain elasticity the materials use means nothing (young = 5e3 Pa for a 5 m slab of density
  // 1800: 18); the shipped scenes strain by 0.013 at most. H is the body's extent along gravity.
  constexpr double kSelfWeightStrain = 0.1;
  if (g > 0.0)
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
      const BodySpec& body = scene.bodies[b];
      const MaterialSpec& m = scene.materials[static_cast<std::size_t>(body.material)];
      double height = 0.0;
      for (int d = 0; d < 3; ++d) height += std::abs(scene.gravity[d]) / g * (body.box_max[d] - body.box_min[d]);
      const double strain = m.density * g * height / m.elastic.young;
      if (strain > kSelfWeightStrain) {
        warnings.push_back(fmt::format(
            "bodies[{}] (\"{}\"): its self-weight strain ρ g H / E = {:.3g} (density {} kg/m³, |g| = {:.4g} m/s², H = "
            "{:.4g} m its extent along gravity, materials.{}.young = {} Pa) is above {}: the body would sag by more "
            "than a tenth of its height under its own weight; young in Pa, not kPa or MPa? (the shipped sand: 2e6 Pa)",
            b, body.name, strain, m.density, g, height, m.name, m.elastic.young, kSelfWeightStrain));
        break;  // one line says it
      }
    }
}

// The gate inside the mass, and a runout plane upslope of the gate.
void add_runout_gate_warnings(const Scene& scene, std::vector<std::string>& warnings) {
  const GridGeometry& grid = scene.grid;
  const double x0 = grid.origin[0], x1 = x0 + grid.cells[0] * grid.h;
  // The gate inside the mass: the runout from the gate starts at the part of the mass already beyond
  // it; a runout plane upslope of the gate: beyond_runout_plane counts from behind the gate.
  if (scene.runout.enabled && !scene.bodies.empty()) {
    const auto [lo, hi] = bodies_footprint_x(scene);
    const double margin = 1e-9 * (std::abs(lo) + std::abs(hi)) + 1e-12;
    if (scene.runout.has_gate && scene.runout.gate_x > lo + margin && scene.runout.gate_x < hi - margin)
      warnings.push_back(fmt::format(
          "diagnostics.runout.gate_x = {} lies inside the bodies' initial extent along x [{:.6g}, {:.6g}]: the "
          "runout from the gate counts the {:.6g} m of the mass already beyond it; put the gate at the bodies' "
          "downslope end (x = {:.6g}) or leave gate_x out (the runout is then measured from the initial front)",
          scene.runout.gate_x, lo, hi, hi - scene.runout.gate_x, hi));
    std::optional<double> plane;
    if (scene.runout.has_runout_plane)
      plane = scene.runout.runout_plane_x;
    else if (grid.has_terrain())
      if (const auto start = TerrainProfile(grid.terrain).last_segment_start(); start && *start >= x0 && *start <= x1)
        plane = start;
    const double gate = scene.runout.has_gate ? scene.runout.gate_x : hi;
    if (plane && *plane < gate - margin)
      warnings.push_back(fmt::format(
          "diagnostics.runout.runout_plane_x = {:.6g}{} is upslope of {} = {:.6g}: the runout plane, where the bed "
          "flattens, starts behind the {}, so beyond_runout_plane counts from behind it; the runout plane lies "
          "downslope (along +x) of the gate",
          *plane, scene.runout.has_runout_plane ? "" : " (its default, the end of the terrain's last transition)",
          scene.runout.has_gate ? "gate_x" : "the bodies' downslope end", gate,
          scene.runout.has_gate ? "gate" : "mass"));
  }
}

// A μ(I) material's solid fraction density / grain_density outside what a packing of grains holds:
// about 0.5 (random loose packing) to 0.74 (the densest packing of spheres). I weighs the grains'
// inertia with grain_density, the mass and the pressure with density: a hunt gave density = grain_density
// (solid fraction 1) and 100 (0.04), both accepted without a word; the shipped scenes have 0.60 and 0.61.
void add_solid_fraction_warning(const Scene& scene, std::vector<std::string>& warnings) {
  constexpr double kLoosest = 0.5, kDensest = 0.74;
  for (const MaterialSpec& m : scene.materials) {
    if (m.model != MaterialModel::MuI) continue;
    const double fraction = m.density / m.mu_i.grain_density;
    if (fraction >= kLoosest && fraction <= kDensest) continue;
    warnings.push_back(fmt::format(
        "materials.{}: density / grain_density = {} / {} = {:.3g}, the packing's solid fraction, is outside [{}, {}] "
        "(random loose packing to the densest packing of spheres): density is the bulk density of the packing, "
        "grain_density that of the grains (a quartz sand: about 1600 and 2650)",
        m.name, m.density, m.mu_i.grain_density, fraction, kLoosest, kDensest));
  }
}

// Gravity pointing up on a flat grid: z is up (the bed is the z- face, the deposit's heights are along
// z), so the bodies fall to the lid. The terrain grid's check says so (add_unit_warnings); a flat
// grid's said nothing. Gravity along x or y alone (the benchmarks) is not warned about.
void add_upward_gravity_warning(const Scene& scene, std::vector<std::string>& warnings) {
  const Vec3& v = scene.gravity;
  if (scene.grid.has_terrain() || !(v[2] > 0.0)) return;
  warnings.push_back(fmt::format(
      "gravity[2] = {} > 0 on a flat grid points up, away from the z- face: z is up, so the bodies fall towards "
      "z+; give gravity[2] < 0 (a tilted incline: [g sin θ, 0, -g cos θ])",
      v[2]));
}

// μ(I) under gravity tilted by θ with tan θ > mu_2 on a flat grid: steady flow needs
// mu_s < tan θ < mu_2 (docs/mu-i.md §8: I_θ = I0 (tan θ - mu_s) / (mu_2 - tan θ); GDR MiDi 2004), since
// the friction never exceeds mu_2; beyond, the layer accelerates without end.
void add_mu_i_tilt_warning(const Scene& scene, std::vector<std::string>& warnings) {
  const Vec3& v = scene.gravity;
  const double along = std::hypot(v[0], v[1]), down = -v[2];
  if (scene.grid.has_terrain() || !(along > 0.0) || !(down > 0.0)) return;  // (upward: the warning above)
  const double slope = along / down;
  for (const MaterialSpec& m : scene.materials)
    if (m.model == MaterialModel::MuI && slope > m.mu_i.mu_2)
      warnings.push_back(fmt::format(
          "gravity = [{}, {}, {}] tilts the flat grid by {:.4g} degrees: tan θ = {:.4g} is above materials.{}.mu_2 = "
          "{:.4g}, the most friction μ(I) gives, so a layer of it has no steady state and accelerates without end "
          "(steady flow needs mu_s < tan θ < mu_2, docs/mu-i.md §8)",
          v[0], v[1], v[2], std::atan(slope) * 180.0 / std::numbers::pi, slope, m.name, m.mu_i.mu_2));
}

}  // namespace

ParticleStore seed_particles(const Scene& scene, const SeedFilter& keep) {
  std::vector<double> densities;
  for (const MaterialSpec& m : scene.materials) densities.push_back(m.density);
  return seed_particles(scene.grid, scene.bodies, densities, body_label(scene), keep);
}

std::vector<std::int64_t> particles_per_x_cell(const Scene& scene) {
  return particles_per_x_cell(scene.grid, scene.bodies, body_label(scene));
}

std::size_t count_particles(const Scene& scene) { return count_particles(scene.grid, scene.bodies, body_label(scene)); }

std::vector<std::string> scene_warnings(const Scene& scene) {
  std::vector<std::string> warnings;
  const double radius = scene.smoothing.mls.radius_factor;
  if (scene.smoothing.enabled && radius > kMlsStableRadiusFactor)
    warnings.push_back(fmt::format(
        "solver.smoothing.radius_factor = {} is above {} cells: MLS smoothing at 3 cells and more went unstable on "
        "the column (1.2 s) and the sliding block (docs/verification.md, \"MLS radius\")",
        radius, kMlsStableRadiusFactor));
  for (std::string& w : seeding_warnings(scene.grid, scene.bodies, body_label(scene))) warnings.push_back(std::move(w));
  for (std::string& w : terrain_warnings(scene.grid, scene.courant)) warnings.push_back(std::move(w));
  for (std::string& w : usage_warnings(scene)) warnings.push_back(std::move(w));
  // On a terrain grid z- is the bed itself, not a face below it: open, it removes whatever settles
  // on the ground (a slide fell through it whole, and only runout.json's outflow share told).
  if (scene.grid.has_terrain() && scene.walls[2][0].type == WallType::Open)
    warnings.push_back(
        "boundaries.z- = \"open\" on a terrain grid: z- is the bed (grid.terrain), so the material leaves through "
        "the ground as it reaches it; give the bed \"friction\", \"slip\" or \"fixed\"");
  // Units written wrong pass every range: a friction coefficient written as an angle in degrees (29
  // for tan 29 degrees), a friction angle written in radians (0.61 for 35 degrees). Warned about
  // where the value is far outside what granular matter shows.
  constexpr double kLikelyDegrees = 2.0;                 // a coefficient tan 63.4 degrees and up
  constexpr double kLikelyRadians = std::numbers::pi / 2;  // an angle of 1.57 degrees and less
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side)
      if (const WallSpec& w = scene.walls[d][side]; w.type == WallType::Friction && w.friction_coefficient >= kLikelyDegrees)
        warnings.push_back(fmt::format(
            "boundaries.{}.friction_coefficient = {} is tan {:.1f} degrees: a coefficient, not an angle in degrees?",
            face_name(d, side), w.friction_coefficient, std::atan(w.friction_coefficient) * 180.0 / std::numbers::pi));
  for (const MaterialSpec& m : scene.materials) {
    if (m.model == MaterialModel::DruckerPrager && m.drucker_prager.friction_angle_deg <= kLikelyRadians)
      warnings.push_back(fmt::format(
          "materials.{}.friction_angle = {} degrees: an angle in degrees, not radians? ({} rad is {:.3g} degrees)",
          m.name, m.drucker_prager.friction_angle_deg, m.drucker_prager.friction_angle_deg,
          m.drucker_prager.friction_angle_deg * 180.0 / std::numbers::pi));
    if (m.model == MaterialModel::MuI && m.mu_i.mu_2 >= kLikelyDegrees)
      warnings.push_back(fmt::format(
          "materials.{}.mu_2 = {} (mu_s = {}) is tan {:.1f} degrees: mu_s and mu_2 are friction coefficients (tan of "
          "the angle), not angles in degrees?",
          m.name, m.mu_i.mu_2, m.mu_i.mu_s, std::atan(m.mu_i.mu_2) * 180.0 / std::numbers::pi));
  }
  // A stiff material or a fine grid can ask for more steps than any run will take: say so before it starts.
  const double dt = scene.initial_time_step(), steps = scene.end_time / dt;
  if (steps > 1e8)
    warnings.push_back(fmt::format("the run would take about {:.3g} steps (initial time step {:.3g} s to time.end = {} s): "
                                   "check the materials' young and density, grid.cell_size and time.end",
                                   steps, dt, scene.end_time));
  // A material so soft that its wave speed no longer bounds the step: the first step (the whole run,
  // for Young's modulus 1 Pa) let the particles fall through the floor, and every such run stopped at
  // its first step with "left the grid".
  const double g = scene.gravity.norm(), first_step = std::min(dt, scene.end_time);
  const double fall_one_cell = g > 0.0 ? std::sqrt(2.0 * scene.grid.h / g) : 0.0;
  if (g > 0.0 && first_step > fall_one_cell)
    warnings.push_back(fmt::format(
        "the first time step, {:.3g} s, is longer than the {:.3g} s a particle at rest takes to fall one cell "
        "(grid.cell_size = {} m) under gravity: the materials' wave speed is too slow to bound the step, and the run "
        "will likely stop in its first steps; check the materials' young and density",
        first_step, fall_one_cell, scene.grid.h));
  // A ramp past the end runs the whole scene under part of its gravity (a ramp meant for the
  // column benchmark's quasi-static loading, copied into a runout scene, say).
  if (scene.gravity_ramp_time > scene.end_time)
    warnings.push_back(fmt::format(
        "solver.gravity_ramp_time = {} s is longer than time.end = {} s: gravity never reaches its full value (at the "
        "end it is {:.3g}% of it)",
        scene.gravity_ramp_time, scene.end_time, 100.0 * scene.end_time / scene.gravity_ramp_time));
  // The runout is measured at each history row, and with no interval that is every step: a sort of
  // every particle by arc length (and under mpirun a gather of them all to rank 0) each step, which
  // made a 244 k-particle flume's run half again as long on one rank (every shipped scene sets it).
  if (scene.runout.enabled && scene.output.history_interval == 0.0)
    warnings.push_back(
        "diagnostics.runout with output.history_interval = 0 measures the runout every step (a sort of every particle, "
        "and under mpirun a gather of them all to rank 0): set output.history_interval (the flumes in inputs/: 0.01 s)");
  // The runout plane's default is where the terrain's last straight segment starts; outside the grid
  // the runout was measured from it all the same ("3.1 m short of the runout plane"), where a
  // runout_plane_x given there is refused. The run leaves it out (RunoutMonitor::result).
  if (scene.runout.enabled && !scene.runout.has_runout_plane && scene.grid.has_terrain()) {
    const GridGeometry& g = scene.grid;
    const double x0 = g.origin[0], x1 = x0 + g.cells[0] * g.h;
    const std::optional<double> plane = TerrainProfile(g.terrain).last_segment_start();
    if (plane && !(*plane >= x0 && *plane <= x1))
      warnings.push_back(fmt::format(
          "diagnostics.runout.runout_plane_x: its default, the end of the terrain's last transition (x = {:.6g} m), "
          "lies outside the grid along x, [{:.12g}, {:.12g}]: the runout is reported without a runout plane; set "
          "runout_plane_x inside the grid to measure from one",
          *plane, x0, x1));
  }
  // An undamped elastic body on a Coulomb face with high friction vibrates, and the vibration makes
  // parts of its base stick or slip backwards: near the sliding threshold (mu = 0.55 on 30 degrees) the
  // effective friction was 0.007 to 0.2 below mu, more on finer grids; at mu = 0.45 up to 0.013, at 0.3
  // none. Sand, which dissipates by plasticity, did not show it (docs/verification.md).
  // Silent from the PIC share that was measured to cure it (0.05); smaller shares were not measured.
  constexpr double kElasticFrictionWarning = 0.45, kMeasuredPicCure = 0.05;
  if (scene.pic_fraction < kMeasuredPicCure)
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
      const BodySpec& body = scene.bodies[b];
      const MaterialSpec& material = scene.materials[static_cast<std::size_t>(body.material)];
      if (material.model != MaterialModel::LinearElastic) continue;
      double mu = 0.0;
      const char* face = "";
      for (int d = 0; d < 3; ++d)
        for (int side = 0; side < 2; ++side)
          if (scene.walls[d][side].type == WallType::Friction && scene.walls[d][side].friction_coefficient > mu) {
            mu = scene.walls[d][side].friction_coefficient;
            face = face_name(d, side);
          }
      if (mu < kElasticFrictionWarning) continue;
      warnings.push_back(fmt::format(
          "bodies[{}] (\"{}\") is linear_elastic on the friction face {} (friction_coefficient {}) with "
          "solver.pic_fraction = {}: near its sliding threshold such a body vibrates and slides with too little "
          "friction, more on finer grids (mu = 0.55 on 30 degrees: 0.007 below mu at h = 0.25 m, 0.02 at 0.125 m; "
          "mu = 0.45: up to 0.013); solver.pic_fraction = 0.05 kept it within 0.005 (docs/verification.md, \"Near "
          "the sliding threshold\")",
          b, body.name, face, mu, scene.pic_fraction));
      break;  // one line says it
    }
  if (scene.smoothing.enabled && scene.smoothing.mls.variant == MlsVariant::Cell)
    warnings.push_back(
        "solver.smoothing.variant = \"cell\" is not energy-stable: one fit per cell fed energy into the elastic block "
        "between walls at radii of 1.5 to 3 cells (docs/verification.md, \"MLS, one fit per cell\"); compare with "
        "\"particle\" before relying on it");
  // The warning is said at an energy row short of the stop; at or above the stop's factor the stop
  // comes first (or at the same row, and the row that trips the guard warns of nothing), so it never is.
  const GuardSpec& guards = scene.guards;
  if (guards.energy_warning_factor > 0.0 && guards.energy_growth_factor > 0.0 &&
      guards.energy_warning_factor >= guards.energy_growth_factor)
    warnings.push_back(fmt::format(
        "guards.energy_warning_factor = {} is not below guards.energy_growth_factor = {}: the energy guard stops "
        "the run before the warning could be said, so it never is; give a warning factor below the stop's (the "
        "default 0.1 against 1), or 0 to turn it off",
        guards.energy_warning_factor, guards.energy_growth_factor));
  add_runout_direction_warning(scene, warnings);
  add_unit_warnings(scene, warnings);
  add_runout_gate_warnings(scene, warnings);
  add_solid_fraction_warning(scene, warnings);
  add_upward_gravity_warning(scene, warnings);
  add_mu_i_tilt_warning(scene, warnings);
  return warnings;
}

}  // namespace talus
