#include "talus/scene/scene_json.hpp"

#include "talus/grid/terrain_profile.hpp"

#include "scene_fields.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/core.h>

namespace talus {

using scene_detail::Json;
using scene_detail::ObjectReader;

namespace {

using scene_detail::SceneDraft;

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

// The first time step comes from each body's wave speed plus its initial speed (Scene::initial_time_step).
// A density of 1e-320 or a velocity of 1e300 m/s passes every range but makes that rate infinite
// and the step zero: the run then stopped at step 0 without saying which body or key was to blame.
void check_time_step(const Scene& s) {
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const BodySpec& body = s.bodies[b];
    const MaterialSpec& m = s.materials[body.material];
    const double wave = s.wave_speed(body), speed = body.velocity.norm();
    const double dt = s.courant * s.grid.h / (wave + speed);
    if (std::isfinite(wave + speed) && std::isnormal(dt)) continue;
    throw input_error(fmt::format(
        "bodies[{}] (\"{}\"): no time step resolves its wave speed sqrt(M / materials.{}.density) = {:.3g} m/s "
        "(density = {:.3g}) plus its speed |bodies[{}].velocity| = {:.3g} m/s",
        b, body.name, m.name, wave, m.density, b, speed));
  }
}

// The runout diagnostics measure along x (the flume coordinate s): on a periodic x axis the flow
// wraps and the front read 0.1 m beyond the gate after 0.5 m of travel; a gate outside the grid
// (gate_x = 1e20) gave a runout of -1e20 m.
void check_runout(const Scene& s) {
  if (!s.runout.enabled) return;
  if (s.grid.periodic[0])
    throw input_error("diagnostics.runout cannot run with periodic x faces (the flow wraps, so no front or runout along x exists)");
  const double x0 = s.grid.origin[0], x1 = x0 + s.grid.cells[0] * s.grid.h;
  if (s.runout.has_gate && !(s.runout.gate_x >= x0 && s.runout.gate_x <= x1))
    throw input_error(fmt::format("diagnostics.runout.gate_x = {} is outside the grid along x, [{:.12g}, {:.12g}]", s.runout.gate_x, x0, x1));
  if (s.runout.has_runout_plane && !(s.runout.runout_plane_x >= x0 && s.runout.runout_plane_x <= x1))
    throw input_error(fmt::format("diagnostics.runout.runout_plane_x = {} is outside the grid along x, [{:.12g}, {:.12g}]",
                                  s.runout.runout_plane_x, x0, x1));
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& source) {
  const Json root = scene_detail::parse_json(text, source);
  SceneDraft draft;
  ObjectReader r(root, "");
  read_fields(r, draft, scene_detail::scene_table());  // every section, in file order of the docs
  check_problem_size(draft.scene);
  check_time_step(draft.scene);
  check_runout(draft.scene);
  return draft.scene;
}

double particle_count_bound(const Scene& s) {
  // Only the part of a body inside the grid can seed particles (the seeding refuses the rest, naming
  // the body): clip its box to the grid's extent first, so that a prism far above a terrain grid is
  // reported as outside it, not as too many particles. With a terrain, z spans the grid's w range
  // over the bed's lowest and highest points within the grid; a box given in the terrain's frame is
  // in w already.
  const GridGeometry& g = s.grid;
  Vec3 lower = g.origin, upper;
  for (int d = 0; d < 3; ++d) upper[d] = g.origin[d] + g.cells[d] * g.h;
  const double w_lower = lower[2], w_upper = upper[2];
  if (g.has_terrain()) {
    const auto [low, high] = TerrainProfile(g.terrain).height_range(lower[0], upper[0]);
    lower[2] += low;
    upper[2] += high;
  }
  double total = 0.0;
  for (const BodySpec& b : s.bodies) {
    const bool in_w = b.frame == BoxFrame::Terrain;
    double count = 1.0;
    for (int d = 0; d < 3; ++d) {
      const double from = d == 2 && in_w ? w_lower : lower[d], to = d == 2 && in_w ? w_upper : upper[d];
      const double lo = std::max(b.box_min[d], from), hi = std::min(b.box_max[d], to);
      count *= hi < lo ? 0.0 : std::floor((hi - lo) * b.particles_per_cell / g.h) + 1.0;
    }
    total += count;
  }
  return total;
}

Scene read_scene_file(const std::string& path) {
  const auto text = scene_detail::read_text_file(path);
  if (!text) throw input_error(fmt::format("cannot open scene file {}{}", path, scene_detail::why_unreadable(path)));
  return parse_scene(*text, path);
}

nlohmann::json scene_to_json(const Scene& s) {
  SceneDraft draft;
  draft.scene = s;
  return write_fields(draft, scene_detail::scene_table());
}

nlohmann::json scene_file_json(const Scene& s) {
  nlohmann::json j = scene_to_json(s);
  for (auto& extent : j.at("grid").at("size")) extent = std::stod(fmt::format("{:.12g}", extent.get<double>()));
  // scene_to_json leaves the default tension cutoff out (the checkpoint's scene hash predates the key);
  // the file a user reads names it, as it names every other default
  for (auto& material : j.at("materials"))
    if (material.value("model", "") == "drucker_prager" && !material.contains("tension_cutoff"))
      material["tension_cutoff"] = "apex";
  return j;
}

}  // namespace talus
