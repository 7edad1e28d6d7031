#include "talus/scene/scene_json.hpp"

#include "json_fields.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace talus {

using scene_detail::Json;
using scene_detail::ObjectReader;

namespace {

constexpr double kHuge = 1e30;
const char* const kFaceNames[3][2] = {{"x-", "x+"}, {"y-", "y+"}, {"z-", "z+"}};

// grid.terrain: the bed z_b(x) (seed 001 eq. 19-20); TerrainProfile checks that it is a graph and
// that the transitions fit, naming the key.
void read_terrain(ObjectReader r, Scene& s) {
  TerrainSpec& t = s.grid.terrain;
  const Json& points = r.raw("points");
  if (!points.is_array() || points.size() < 2)
    throw input_error(fmt::format("{} must be an array of at least 2 [x, z] points, got {}", r.key_path("points"),
                                  points.dump()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string at = fmt::format("{}[{}]", r.key_path("points"), i);
    if (!points[i].is_array() || points[i].size() != 2)
      throw input_error(fmt::format("{} must be an [x, z] pair of numbers, got {}", at, points[i].dump()));
    t.points.push_back({ObjectReader::check_number(points[i][0], at + "[0]", -kHuge, kHuge, false, false),
                        ObjectReader::check_number(points[i][1], at + "[1]", -kHuge, kHuge, false, false)});
  }
  if (r.has("radii")) {
    const Json& radii = r.raw("radii");
    if (!radii.is_array())
      throw input_error(fmt::format("{} must be an array of numbers >= 0, one per point", r.key_path("radii")));
    for (std::size_t i = 0; i < radii.size(); ++i)
      t.radii.push_back(
          ObjectReader::check_number(radii[i], fmt::format("{}[{}]", r.key_path("radii"), i), 0.0, kHuge, false, false));
  }
  r.finish();
  (void)TerrainProfile(t);  // validates: a graph z_b(x), transitions that fit
}

void read_grid(ObjectReader r, Scene& s) {
  s.grid.origin = r.vec3_or("origin", Vec3::Zero());
  const double h = r.number("cell_size", 0.0, kHuge, true);
  const Vec3 size = r.vec3("size", 0.0, kHuge);
  s.grid.h = h;
  for (int d = 0; d < 3; ++d) {
    const double n = size[d] / h;
    const long long cells = std::llround(n);
    if (cells < 1 || std::abs(n - static_cast<double>(cells)) > 1e-6 * std::max(1.0, n))
      throw input_error(fmt::format("{}[{}] = {} must be a positive whole multiple of {} = {}", r.key_path("size"), d,
                                    size[d], r.key_path("cell_size"), h));
    if (cells > 100000)
      throw input_error(fmt::format("{}[{}] / cell_size = {} cells; at most 100000 per axis", r.key_path("size"), d, cells));
    s.grid.cells[d] = static_cast<int>(cells);
  }
  if (r.has("terrain")) read_terrain(r.object("terrain"), s);
  r.finish();
}

void read_time(ObjectReader r, Scene& s) {
  s.end_time = r.number("end", 0.0, kHuge, true);
  s.courant = r.number_or("courant", s.courant, 0.0, 1.0, true, true);
  s.max_steps = r.integer_or("max_steps", 0, 0, 2000000000);
  r.finish();
}

// MLS smoothing (seed 000 eq. 38-46, 54). Body names are resolved once the bodies are read.
void read_smoothing(ObjectReader r, Scene& s, std::vector<std::string>& body_names) {
  SmoothingSpec& m = s.smoothing;
  m.enabled = r.boolean_or("enabled", true);
  const std::string basis = r.choice("basis", "linear", {"linear", "quadratic", "cubic"});
  m.mls.basis = basis == "cubic" ? MlsBasis::Cubic : basis == "quadratic" ? MlsBasis::Quadratic : MlsBasis::Linear;
  m.mls.radius_factor = r.number_or("radius_factor", m.mls.radius_factor, 0.5, 8.0);
  const std::string axes = r.choice("axes", "xyz", {"xyz", "xy", "xz", "yz", "x", "y", "z"});
  for (int d = 0; d < 3; ++d) m.mls.axes[d] = axes.find(static_cast<char>('x' + d)) != std::string::npos;
  m.mls.min_rcond = r.number_or("min_rcond", m.mls.min_rcond, 0.0, 1.0, true, true);
  if (r.has("bodies")) {
    const Json& b = r.raw("bodies");
    if (!b.is_array() || b.empty())
      throw input_error(fmt::format("{} must be a non-empty array of body names, got {}", r.key_path("bodies"), b.dump()));
    for (std::size_t i = 0; i < b.size(); ++i) {
      if (!b[i].is_string())
        throw input_error(fmt::format("{}[{}] must be a body name (string), got {}", r.key_path("bodies"), i, b[i].dump()));
      body_names.push_back(b[i].get<std::string>());
    }
  }
  r.finish();
}

void resolve_smoothing_bodies(const std::vector<std::string>& names, Scene& s) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    int found = -1;
    std::string known;
    for (std::size_t b = 0; b < s.bodies.size(); ++b) {
      if (s.bodies[b].name == names[i]) found = static_cast<int>(b);
      known += (known.empty() ? "" : ", ") + s.bodies[b].name;
    }
    if (found < 0)
      throw input_error(fmt::format("solver.smoothing.bodies[{}] = \"{}\" names no body (defined: {})", i, names[i], known));
    if (std::find(s.smoothing.bodies.begin(), s.smoothing.bodies.end(), found) == s.smoothing.bodies.end())
      s.smoothing.bodies.push_back(found);
  }
}

std::string axes_name(const std::array<bool, 3>& axes) {
  std::string a;
  for (int d = 0; d < 3; ++d)
    if (axes[d]) a += static_cast<char>('x' + d);
  return a;
}

void read_solver(ObjectReader r, Scene& s, std::vector<std::string>& smoothing_bodies) {
  const std::string scheme = r.choice("scheme", "musl", {"musl", "usl", "usf", "usavg"});
  s.scheme = scheme == "usl"     ? SchemeKind::Usl
             : scheme == "usf"   ? SchemeKind::Usf
             : scheme == "usavg" ? SchemeKind::Usavg
                                 : SchemeKind::Musl;
  const std::string shape = r.choice("shape", "linear", {"linear", "ugimp", "cpgimp", "bspline2"});
  s.shape = shape == "ugimp"      ? ShapeKind::UGimp
            : shape == "cpgimp"   ? ShapeKind::CpGimp
            : shape == "bspline2" ? ShapeKind::BSpline2
                                  : ShapeKind::Linear;
  s.sort_interval = r.integer_or("sort_interval", s.sort_interval, 1, 1000000);
  s.gravity_ramp_time = r.number_or("gravity_ramp_time", s.gravity_ramp_time, 0.0, kHuge);
  s.pic_fraction = r.number_or("pic_fraction", s.pic_fraction, 0.0, 1.0);
  if (r.has("smoothing")) read_smoothing(r.object("smoothing"), s, smoothing_bodies);
  r.finish();
}

ConeFit read_cone(ObjectReader& r) {
  const std::string cone = r.choice("cone", "plane_strain", {"plane_strain", "compression", "extension", "inscribed"});
  if (cone == "compression") return ConeFit::Compression;
  if (cone == "extension") return ConeFit::Extension;
  if (cone == "inscribed") return ConeFit::Inscribed;
  return ConeFit::PlaneStrain;
}

// The separation rule shared by the granular models: stress-free beyond V / V0 = ratio, 0 disables.
void read_separation(ObjectReader& r, GranularOptions& g) {
  g.separation_volume_ratio = r.number_or("separation_volume_ratio", g.separation_volume_ratio, 0.0, kHuge);
  if (g.separation_volume_ratio != 0.0 && g.separation_volume_ratio <= 1.0)
    throw input_error(fmt::format("{} = {} is outside the allowed range (1, inf), or 0 to disable",
                                  r.key_path("separation_volume_ratio"), g.separation_volume_ratio));
}

// Drucker-Prager keys next to density/young/poisson (seed 001 eq. 23-25, Table 2); the ranges are
// checked by the DruckerPrager constructor, which names the key path.
void read_drucker_prager(ObjectReader& r, MaterialSpec& m) {
  DruckerPragerParameters& p = m.drucker_prager;
  p.young = m.elastic.young;
  p.poisson = m.elastic.poisson;
  auto any_number = [&](const char* key, double fallback) {
    return r.number_or(key, fallback, -kHuge, kHuge);  // range checked below, with the allowed interval
  };
  p.friction_angle_deg = r.number("friction_angle", -kHuge, kHuge);  // required
  p.dilatancy_angle_deg = any_number("dilatancy_angle", 0.0);
  p.cohesion = any_number("cohesion", 0.0);
  p.hardening_modulus = any_number("hardening_modulus", 0.0);
  p.kinematic_fraction = any_number("kinematic_fraction", 0.0);
  if (r.has("tension_cutoff")) p.tension_cutoff = any_number("tension_cutoff", 0.0);
  p.cone = read_cone(r);
  const std::string prefix = r.path() + ".";
  (void)DruckerPrager(p, prefix);  // validates, throws with the key path and the allowed range
  GranularOptions& g = m.granular;
  g.flowing_plastic_strain = r.number_or("flowing_plastic_strain", g.flowing_plastic_strain, 0.0, kHuge);
  g.flowing_dilatancy_angle_deg =
      r.number_or("flowing_dilatancy_angle", g.flowing_dilatancy_angle_deg, 0.0, p.friction_angle_deg);
  read_separation(r, g);
}

// μ(I) keys next to density/young/poisson (Jop et al. 2006, friction law and inertial number; docs/mu-i.md); defaults are the
// glass beads of Jop et al. 2006; the ranges are checked by the MuI constructor, which names the key.
void read_mu_i(ObjectReader& r, MaterialSpec& m) {
  MuIParameters& p = m.mu_i;
  p.young = m.elastic.young;
  p.poisson = m.elastic.poisson;
  auto any_number = [&](const char* key, double fallback) {
    return r.number_or(key, fallback, -kHuge, kHuge);  // range checked below, with the allowed interval
  };
  p.mu_s = any_number("mu_s", p.mu_s);
  p.mu_2 = any_number("mu_2", p.mu_2);
  p.i0 = any_number("i0", p.i0);
  p.grain_diameter = any_number("grain_diameter", p.grain_diameter);
  p.grain_density = any_number("grain_density", p.grain_density);
  (void)MuI(p, r.path() + ".");  // validates, throws with the key path and the allowed range
  read_separation(r, m.granular);
}

MaterialSpec read_material(ObjectReader r, const std::string& name) {
  MaterialSpec m;
  m.name = name;
  const std::string model = r.choice("model", "linear_elastic", {"linear_elastic", "drucker_prager", "mu_i"});
  m.model = model == "drucker_prager" ? MaterialModel::DruckerPrager
            : model == "mu_i"         ? MaterialModel::MuI
                                      : MaterialModel::LinearElastic;
  m.density = r.number("density", 0.0, kHuge, true);
  m.elastic.young = r.number("young", 0.0, kHuge, true);
  if (m.model == MaterialModel::DruckerPrager) {
    m.elastic.poisson = r.number("poisson", 0.0, 0.5, false, true);
    read_drucker_prager(r, m);
  } else if (m.model == MaterialModel::MuI) {
    m.elastic.poisson = r.number("poisson", 0.0, 0.5, false, true);
    read_mu_i(r, m);
  } else {
    m.elastic.poisson = r.number("poisson", -1.0, 0.5, true, true);
  }
  r.finish();
  return m;
}

// The body's bounding box must lie in the grid. (On a terrain grid the third axis is w = z - z_b(x):
// the terrain branch maps this check.)
void check_inside_grid(const BodySpec& b, const std::string& path, const Scene& s) {
  for (int d = 0; d < 3; ++d) {
    // A physical body on a terrain grid is checked against the bed when seeding (seeding.cpp): the
    // grid's z range depends on x there.
    if (d == 2 && s.grid.has_terrain() && b.frame == BoxFrame::Physical) continue;
    const double lo = s.grid.origin[d];
    const double hi = lo + s.grid.cells[d] * s.grid.h;
    if (b.box_min[d] < lo - 1e-12 * std::abs(lo) || b.box_max[d] > hi + 1e-12 * std::abs(hi))
      throw input_error(fmt::format("{} [{}, {}] along axis {} lies outside the grid [{}, {}]", path, b.box_min[d],
                                    b.box_max[d], d, lo, hi));
  }
}

// "prism": {"points": [[x, z], ...], "y": [y0, y1]}: a simple polygon in the x-z plane, extruded.
void read_prism(ObjectReader r, BodySpec& b) {
  b.shape = BodyShapeKind::Prism;
  const Json& pts = r.raw("points");
  const std::string points_path = r.key_path("points");
  if (!pts.is_array() || pts.size() < 3)
    throw input_error(fmt::format("{} must be an array of at least 3 [x, z] points, got {}", points_path,
                                  pts.is_array() ? fmt::format("{} points", pts.size()) : pts.dump()));
  if (pts.size() > 10000) throw input_error(fmt::format("{} has {} points; at most 10000", points_path, pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::string at = fmt::format("{}[{}]", points_path, i);
    if (!pts[i].is_array() || pts[i].size() != 2)
      throw input_error(fmt::format("{} must be an [x, z] pair of numbers, got {}", at, pts[i].dump()));
    std::array<double, 2> p;
    for (int c = 0; c < 2; ++c)
      p[c] = ObjectReader::check_number(pts[i][c], fmt::format("{}[{}]", at, c), -kHuge, kHuge, false, false);
    b.prism.points.push_back(p);
  }
  const auto crossing = polygon_crossing_edges(b.prism.points);
  if (crossing[0] >= 0)
    throw input_error(fmt::format("{} is not a simple polygon: edge {} (points {} to {}) touches edge {} (points {} to {})",
                                  points_path, crossing[0], crossing[0], (crossing[0] + 1) % pts.size(), crossing[1],
                                  crossing[1], (crossing[1] + 1) % pts.size()));
  if (polygon_signed_area(b.prism.points) == 0.0)
    throw input_error(fmt::format("{} encloses no area", points_path));
  const Json& y = r.raw("y");
  if (!y.is_array() || y.size() != 2)
    throw input_error(fmt::format("{} must be [y0, y1] with y0 < y1, got {}", r.key_path("y"), y.dump()));
  b.prism.y0 = ObjectReader::check_number(y[0], r.key_path("y") + "[0]", -kHuge, kHuge, false, false);
  b.prism.y1 = ObjectReader::check_number(y[1], r.key_path("y") + "[1]", -kHuge, kHuge, false, false);
  if (!(b.prism.y0 < b.prism.y1))
    throw input_error(fmt::format("{} = [{}, {}] must have y0 < y1", r.key_path("y"), b.prism.y0, b.prism.y1));
  r.finish();
  b.box_min = Vec3(kHuge, b.prism.y0, kHuge);
  b.box_max = Vec3(-kHuge, b.prism.y1, -kHuge);
  for (const auto& p : b.prism.points) {
    b.box_min[0] = std::min(b.box_min[0], p[0]);
    b.box_max[0] = std::max(b.box_max[0], p[0]);
    b.box_min[2] = std::min(b.box_min[2], p[1]);
    b.box_max[2] = std::max(b.box_max[2], p[1]);
  }
}

BodySpec read_body(ObjectReader r, const Scene& s, const std::map<std::string, int>& materials) {
  BodySpec b;
  b.name = r.string("name");
  const std::string material = r.string("material");
  auto it = materials.find(material);
  if (it == materials.end()) {
    std::string known;
    for (const auto& [k, v] : materials) known += (known.empty() ? "" : ", ") + k;
    throw input_error(fmt::format("{} = \"{}\" names no material (defined: {})", r.key_path("material"), material, known));
  }
  b.material = it->second;
  if (r.has("box") == r.has("prism"))
    throw input_error(fmt::format("{} needs exactly one shape: \"box\" or \"prism\"", r.path()));
  if (r.has("box")) {
    ObjectReader box = r.object("box");
    b.box_min = box.vec3("min");
    b.box_max = box.vec3("max");
    if (box.has("frame")) {
      if (!s.grid.has_terrain())
        throw input_error(fmt::format("{} needs grid.terrain (on a flat grid z is the height above the floor)",
                                      box.key_path("frame")));
      b.frame = box.choice("frame", "physical", {"physical", "terrain"}) == "terrain" ? BoxFrame::Terrain
                                                                                       : BoxFrame::Physical;
    }
    box.finish();
    for (int d = 0; d < 3; ++d)
      if (!(b.box_min[d] < b.box_max[d]))
        throw input_error(fmt::format("{}.min[{}] = {} must be below max[{}] = {}", box.path(), d, b.box_min[d], d, b.box_max[d]));
    check_inside_grid(b, box.path(), s);
  } else {
    read_prism(r.object("prism"), b);
    check_inside_grid(b, r.key_path("prism"), s);
  }
  b.particles_per_cell = r.integer_or("particles_per_cell", b.particles_per_cell, 1, 8);
  b.velocity = r.vec3_or("velocity", Vec3::Zero());
  r.finish();
  return b;
}

WallSpec read_wall(const Json& j, const std::string& path) {
  WallSpec w;
  auto parse_type = [&](const std::string& t, const std::string& at) {
    if (t == "open") return WallType::Open;
    if (t == "slip") return WallType::Slip;
    if (t == "fixed") return WallType::Fixed;
    if (t == "friction") return WallType::Friction;
    throw input_error(fmt::format("{} = \"{}\" is not one of: open, slip, fixed, friction", at, t));
  };
  if (j.is_string()) {
    w.type = parse_type(j.get<std::string>(), path);
    if (w.type == WallType::Friction)
      throw input_error(fmt::format("{} = \"friction\" needs an object with friction_coefficient", path));
    return w;
  }
  ObjectReader r(j, path);
  w.type = parse_type(r.string("type"), r.key_path("type"));
  if (w.type == WallType::Friction) w.friction_coefficient = r.number("friction_coefficient", 0.0, 100.0);
  r.finish();
  return w;
}

void read_boundaries(ObjectReader r, Scene& s) {
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side)
      if (r.has(kFaceNames[d][side])) s.walls[d][side] = read_wall(r.raw(kFaceNames[d][side]), r.key_path(kFaceNames[d][side]));
  r.finish();
}

void read_output(ObjectReader r, Scene& s) {
  s.output.frame_interval = r.number_or("frame_interval", 0.0, 0.0, kHuge);
  s.output.history_interval = r.number_or("history_interval", 0.0, 0.0, kHuge);
  s.output.compress = r.choice("compression", "lz4", {"lz4", "none"}) == "lz4";
  s.output.checkpoint_interval = r.number_or("checkpoint_interval", 0.0, 0.0, kHuge);
  r.finish();
}

// What cannot be allocated is bad input too (docs/reliability.md): a one-line refusal, not a crash.
void check_problem_size(const Scene& s) {
  const double cells = double(s.grid.cells[0]) * s.grid.cells[1] * s.grid.cells[2];
  if (cells > 1e9)
    throw input_error(fmt::format("grid.size / grid.cell_size = {} x {} x {} = {:.3g} cells; at most 1e9", s.grid.cells[0],
                                  s.grid.cells[1], s.grid.cells[2], cells));
  const double particles = particle_count_bound(s);
  if (particles > 2147483647.0)
    throw input_error(fmt::format("bodies seed about {:.3g} particles; at most 2^31 (fewer bodies, larger cell_size or "
                                  "fewer particles_per_cell)", particles));
}

// Instability guards (docs/reliability.md).
void read_guards(ObjectReader r, Scene& s) {
  GuardSpec& g = s.guards;
  g.max_step_displacement = r.number_or("max_step_displacement", g.max_step_displacement, 0.0, 2.0, true);
  g.energy_growth_factor = r.number_or("energy_growth_factor", g.energy_growth_factor, 0.0, kHuge, true);
  g.snapshot_interval = r.integer_or("snapshot_interval", g.snapshot_interval, 0, 1000000);
  r.finish();
}

// "diagnostics": {"runout": {...}} (docs/flume.md "Runout diagnostics").
void read_diagnostics(ObjectReader r, Scene& s) {
  if (r.has("runout")) {
    ObjectReader d = r.object("runout");
    RunoutSpec& rs = s.runout;
    rs.enabled = true;
    rs.front_quantile = d.number_or("front_quantile", rs.front_quantile, 0.5, 1.0, false, false);
    rs.tail_quantile = d.number_or("tail_quantile", rs.tail_quantile, 0.0, 0.5, false, false);
    rs.has_gate = d.has("gate_x");
    rs.gate_x = d.number_or("gate_x", 0.0, -kHuge, kHuge);
    rs.has_runout_plane = d.has("runout_plane_x");
    rs.runout_plane_x = d.number_or("runout_plane_x", 0.0, -kHuge, kHuge);
    rs.deposit_cell = d.number_or("deposit_cell", s.grid.h, 0.0, kHuge, true);
    const double raster_cells = (s.grid.cells[0] * s.grid.h / rs.deposit_cell) * (s.grid.cells[1] * s.grid.h / rs.deposit_cell);
    if (raster_cells > 1e7)
      throw input_error(fmt::format("{} = {} makes a deposit raster of {:.3g} cells over the grid; at most 1e7",
                                    d.key_path("deposit_cell"), rs.deposit_cell, raster_cells));
    d.finish();
  }
  r.finish();
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& source) {
  Json root;
  try {
    root = Json::parse(text);
  } catch (const Json::exception& e) {
    // nlohmann's message already names the line and column. Not only parse_error: a number that
    // overflows a double (1e999) is an out_of_range error.
    std::string what = e.what();
    const auto bracket = what.find(']');
    throw input_error(fmt::format("{}: malformed JSON: {}", source, bracket == std::string::npos ? what : what.substr(bracket + 2)));
  }
  Scene s;
  ObjectReader r(root, "");
  r.allow("comment");
  s.name = r.string_or("name", "scene");
  s.description = r.string_or("description", "");
  read_grid(r.object("grid"), s);
  s.gravity = r.vec3_or("gravity", s.gravity);
  read_time(r.object("time"), s);
  std::vector<std::string> smoothing_bodies;
  if (r.has("solver")) read_solver(r.object("solver"), s, smoothing_bodies);

  std::map<std::string, int> material_index;
  {
    ObjectReader mats = r.object("materials");
    const Json& mj = root.at("materials");
    for (auto it = mj.begin(); it != mj.end(); ++it) {
      mats.allow(it.key());
      material_index[it.key()] = static_cast<int>(s.materials.size());
      s.materials.push_back(read_material(ObjectReader(it.value(), mats.key_path(it.key())), it.key()));
    }
    if (s.materials.empty()) throw input_error("materials must define at least one material");
  }
  {
    const Json& bj = r.raw("bodies");
    if (!bj.is_array() || bj.empty()) throw input_error("bodies must be a non-empty array of bodies");
    if (bj.size() > 65535) throw input_error("bodies: at most 65535 bodies");
    for (std::size_t i = 0; i < bj.size(); ++i)
      s.bodies.push_back(read_body(ObjectReader(bj[i], fmt::format("bodies[{}]", i)), s, material_index));
  }
  resolve_smoothing_bodies(smoothing_bodies, s);
  if (r.has("boundaries")) read_boundaries(r.object("boundaries"), s);
  if (r.has("output")) read_output(r.object("output"), s);
  if (r.has("guards")) read_guards(r.object("guards"), s);
  if (r.has("diagnostics")) read_diagnostics(r.object("diagnostics"), s);
  r.finish();
  check_problem_size(s);
  return s;
}

double particle_count_bound(const Scene& s) {
  double total = 0.0;
  for (const BodySpec& b : s.bodies) {
    double count = 1.0;
    for (int d = 0; d < 3; ++d) count *= std::floor((b.box_max[d] - b.box_min[d]) * b.particles_per_cell / s.grid.h) + 1.0;
    total += count;
  }
  return total;
}

Scene read_scene_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw input_error(fmt::format("cannot open scene file {}", path));
  std::stringstream text;
  text << in.rdbuf();
  return parse_scene(text.str(), path);
}

nlohmann::json scene_to_json(const Scene& s) {
  auto vec = [](const Vec3& v) { return Json::array({v[0], v[1], v[2]}); };
  Json j;
  j["name"] = s.name;
  j["description"] = s.description;
  j["grid"] = {{"origin", vec(s.grid.origin)},
               {"cell_size", s.grid.h},
               {"size", Json::array({s.grid.cells[0] * s.grid.h, s.grid.cells[1] * s.grid.h, s.grid.cells[2] * s.grid.h})}};
  if (s.grid.has_terrain()) {
    Json points = Json::array();
    for (const auto& p : s.grid.terrain.points) points.push_back(Json::array({p[0], p[1]}));
    Json radii = Json::array();
    for (std::size_t i = 0; i < s.grid.terrain.points.size(); ++i)
      radii.push_back(s.grid.terrain.radii.empty() ? 0.0 : s.grid.terrain.radii[i]);
    j["grid"]["terrain"] = {{"points", points}, {"radii", radii}};
  }
  j["gravity"] = vec(s.gravity);
  j["time"] = {{"end", s.end_time}, {"courant", s.courant}, {"max_steps", s.max_steps}};
  j["solver"] = {{"scheme", to_string(s.scheme)},
                 {"shape", to_string(s.shape)},
                 {"sort_interval", s.sort_interval},
                 {"gravity_ramp_time", s.gravity_ramp_time}, {"pic_fraction", s.pic_fraction}};
  {
    Json names = Json::array();
    for (std::size_t b = 0; b < s.bodies.size(); ++b)
      if (s.smoothing.bodies.empty() || std::find(s.smoothing.bodies.begin(), s.smoothing.bodies.end(), int(b)) != s.smoothing.bodies.end())
        names.push_back(s.bodies[b].name);
    j["solver"]["smoothing"] = {{"enabled", s.smoothing.enabled},
                                {"basis", to_string(s.smoothing.mls.basis)},
                                {"radius_factor", s.smoothing.mls.radius_factor},
                                {"axes", axes_name(s.smoothing.mls.axes)},
                                {"min_rcond", s.smoothing.mls.min_rcond},
                                {"bodies", names}};
  }
  Json mats = Json::object();
  for (const auto& m : s.materials) {
    Json mj = {{"model", to_string(m.model)}, {"density", m.density}, {"young", m.elastic.young}, {"poisson", m.elastic.poisson}};
    if (m.model == MaterialModel::DruckerPrager) {
      const DruckerPragerParameters& p = m.drucker_prager;
      mj["friction_angle"] = p.friction_angle_deg;
      mj["dilatancy_angle"] = p.dilatancy_angle_deg;
      mj["cohesion"] = p.cohesion;
      mj["hardening_modulus"] = p.hardening_modulus;
      mj["kinematic_fraction"] = p.kinematic_fraction;
      if (std::isfinite(p.tension_cutoff)) mj["tension_cutoff"] = p.tension_cutoff;
      mj["cone"] = to_string(p.cone);
      mj["flowing_plastic_strain"] = m.granular.flowing_plastic_strain;
      mj["flowing_dilatancy_angle"] = m.granular.flowing_dilatancy_angle_deg;
      mj["separation_volume_ratio"] = m.granular.separation_volume_ratio;
    } else if (m.model == MaterialModel::MuI) {
      const MuIParameters& p = m.mu_i;
      mj["mu_s"] = p.mu_s;
      mj["mu_2"] = p.mu_2;
      mj["i0"] = p.i0;
      mj["grain_diameter"] = p.grain_diameter;
      mj["grain_density"] = p.grain_density;
      mj["separation_volume_ratio"] = m.granular.separation_volume_ratio;
    }
    mats[m.name] = mj;
  }
  j["materials"] = mats;
  Json bodies = Json::array();
  for (const auto& b : s.bodies) {
    Json bj = {{"name", b.name}, {"material", s.materials[b.material].name}};
    if (b.shape == BodyShapeKind::Prism) {
      Json pts = Json::array();
      for (const auto& p : b.prism.points) pts.push_back(Json::array({p[0], p[1]}));
      bj["prism"] = {{"points", pts}, {"y", Json::array({b.prism.y0, b.prism.y1})}};
    } else {
      bj["box"] = {{"min", vec(b.box_min)}, {"max", vec(b.box_max)}};
      if (b.frame == BoxFrame::Terrain) bj["box"]["frame"] = "terrain";
    }
    bj["particles_per_cell"] = b.particles_per_cell;
    bj["velocity"] = vec(b.velocity);
    bodies.push_back(bj);
  }
  j["bodies"] = bodies;
  Json walls = Json::object();
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      const WallSpec& w = s.walls[d][side];
      if (w.type == WallType::Friction)
        walls[kFaceNames[d][side]] = {{"type", "friction"}, {"friction_coefficient", w.friction_coefficient}};
      else
        walls[kFaceNames[d][side]] = to_string(w.type);
    }
  j["boundaries"] = walls;
  j["output"] = {{"frame_interval", s.output.frame_interval},
                 {"history_interval", s.output.history_interval},
                 {"compression", s.output.compress ? "lz4" : "none"},
                 {"checkpoint_interval", s.output.checkpoint_interval}};
  if (s.runout.enabled) {
    Json runout = {{"front_quantile", s.runout.front_quantile},
                   {"tail_quantile", s.runout.tail_quantile},
                   {"deposit_cell", s.runout.deposit_cell}};
    if (s.runout.has_gate) runout["gate_x"] = s.runout.gate_x;
    if (s.runout.has_runout_plane) runout["runout_plane_x"] = s.runout.runout_plane_x;
    j["diagnostics"] = {{"runout", runout}};
  }
  j["guards"] = {{"max_step_displacement", s.guards.max_step_displacement},
                 {"energy_growth_factor", s.guards.energy_growth_factor},
                 {"snapshot_interval", s.guards.snapshot_interval}};
  return j;
}

}  // namespace talus
