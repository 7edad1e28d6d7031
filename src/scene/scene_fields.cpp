// The scene file, section by section: every key once, with its type, default, range and meaning
// (docs/scene-reference.md is made from these rows by `talus schema --markdown`). Keys the table
// factories cannot express (arrays of points, names resolved later, walls given as a word or an
// object) are `custom` entries, read and written here by hand.
#include "scene_fields.hpp"

#include "talus/core/polygon.hpp"
#include "talus/grid/terrain_profile.hpp"
#include "talus/particles/cell_sort.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace talus::scene_detail {

// The place of a value in the object a table reads (a generic lambda: const for the writer).
#define TALUS_AT(member) [](auto& d) -> auto& { return d.member; }

namespace {

/// The words of a choice: each value's to_string (scene.hpp), so an enum's names are written once.
template <class E>
std::vector<std::pair<std::string, E>> named(std::initializer_list<E> values) {
  std::vector<std::pair<std::string, E>> out;
  for (E v : values) out.emplace_back(to_string(v), v);
  return out;
}

Json point_pairs_schema(std::size_t min_items) {
  return {{"type", "array"},
          {"minItems", min_items},
          {"items", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}}}};
}

/// An array of [x, z] pairs (terrain points, prism vertices), each number finite.
PolygonPoints read_point_pairs(const Json& points, const std::string& path) {
  PolygonPoints out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string at = fmt::format("{}[{}]", path, i);
    if (!points[i].is_array() || points[i].size() != 2)
      throw input_error(fmt::format("{} must be an [x, z] pair of numbers, got {}", at, points[i].dump()));
    out.push_back({ObjectReader::check_number(points[i][0], at + "[0]", -kHuge, kHuge, false, false),
                   ObjectReader::check_number(points[i][1], at + "[1]", -kHuge, kHuge, false, false)});
  }
  return out;
}

Json point_pairs_json(const PolygonPoints& points) {
  Json out = Json::array();
  for (const auto& p : points) out.push_back(Json::array({p[0], p[1]}));
  return out;
}

// ---- grid ----------------------------------------------------------------------------------------

// grid.terrain: the bed z_b(x) (Abe, Johansson & Konagai 2005, eq. 19-20); TerrainProfile checks
// that it is a graph and that the transitions fit, naming the key.
Table<SceneDraft> make_terrain_table() {
  return {{
      custom<SceneDraft>(
          "points", "[[x, z], …]", "none (flat grid)", "≥ 2 points, finite, x strictly increasing",
          "bed profile z_b(x), piecewise linear, uniform across y; beyond the end points the end segments continue. "
          "With a terrain the third grid coordinate is w = z − z_b(x): `grid.origin[2]` and `grid.size[2]` are in w, "
          "and the `z-` face (w = origin[2], normally 0) is the bed (docs/theory.md \"Terrain-following grid\"). Warned "
          "about: a chord between two node columns so steep that courant / cos θ passes 1.5 (the sheared cells no longer "
          "bound the step; docs/theory.md \"How steep\"), a profile more than 1% longer over the whole grid than those "
          "chords (the runout would be measured along a longer bed than the particles slide on), grid.origin[2] ≠ 0, "
          "and points that stop more than a cell short of either end of the grid along x (the bed there is the end "
          "segment continued)",
          point_pairs_schema(2),
          [](ObjectReader& r, SceneDraft& d) {
            const Json& points = r.raw("points");
            if (!points.is_array() || points.size() < 2)
              throw input_error(fmt::format("{} must be an array of at least 2 [x, z] points, got {}",
                                            r.key_path("points"), points.dump()));
            d.scene.grid.terrain.points = read_point_pairs(points, r.key_path("points"));
          },
          [](const SceneDraft& d, Json& j) { j["points"] = point_pairs_json(d.scene.grid.terrain.points); },
          {.required = true, .fallback = "none (flat grid)"}),
      custom<SceneDraft>(
          "radii", "[r per point]", "all 0", "≥ 0, one per point; transitions must fit on their segments",
          "radius of the circular transition at each interior point (0: sharp kink; end points ignored). The grid's "
          "bed is the profile sampled at the node columns: a transition departs from it by ≤ h²/(8r cos³θ) along the vertical, θ the steepest slope on the arc (h²/8r where it is gentle); a sharp kink "
          "between node columns is cut by a chord, so put kinks on node columns or use r ≥ 2h (`run` and `check` warn "
          "where a vertex with r < 2h lies between node columns and the chord passes more than h/16 from it)",
          {{"type", "array"}, {"items", {{"type", "number"}, {"minimum", 0}}}},
          [](ObjectReader& r, SceneDraft& d) {
            if (!r.has("radii")) return;
            const Json& radii = r.raw("radii");
            if (!radii.is_array())
              throw input_error(fmt::format("{} must be an array of numbers >= 0, one per point", r.key_path("radii")));
            for (std::size_t i = 0; i < radii.size(); ++i)
              d.scene.grid.terrain.radii.push_back(ObjectReader::check_number(
                  radii[i], fmt::format("{}[{}]", r.key_path("radii"), i), 0.0, kHuge, false, false));
          },
          [](const SceneDraft& d, Json& j) {
            const TerrainSpec& t = d.scene.grid.terrain;
            Json radii = Json::array();
            for (std::size_t i = 0; i < t.points.size(); ++i) radii.push_back(t.radii.empty() ? 0.0 : t.radii[i]);
            j["radii"] = radii;
          }),
  }};
}
constexpr auto terrain_table = &table_of<SceneDraft, make_terrain_table>;

Table<SceneDraft> make_grid_table() {
  return {{
      vec3<SceneDraft>("origin", TALUS_AT(scene.grid.origin), "corner of the domain"),
      number<SceneDraft>("cell_size", TALUS_AT(scene.grid.h), {0.0, kHuge, true}, "cell size h (cubic cells)",
                         {.required = true}),
      custom<SceneDraft>(
          "size", "[Lx, Ly, Lz]", "", "whole multiples of `cell_size`, at most 100000 cells per axis",
          "extent of the domain",
          {{"type", "array"}, {"items", {{"type", "number"}, {"exclusiveMinimum", 0}}}, {"minItems", 3}, {"maxItems", 3}},
          [](ObjectReader& r, SceneDraft& d) {
            GridGeometry& g = d.scene.grid;
            const Vec3 size = r.vec3("size", 0.0, kHuge, /*open_lo=*/true);  // (0 was refused as no multiple, after "[0, inf)")
            for (int a = 0; a < 3; ++a) {
              const double n = size[a] / g.h;
              // The limit first: past about 9.2e18 cells llround has no result (a cell_size of 1e-20 was
              // called no whole divisor of the size), and any count past the limit is refused for it.
              constexpr double kMaxCells = 100000;
              if (n > kMaxCells + 0.5)
                throw input_error(fmt::format("{}[{}] / {} = {:.6g} cells; at most {} per axis", r.key_path("size"), a,
                                              r.key_path("cell_size"), n, kMaxCells));
              const long long cells = std::llround(n);
              if (cells < 1 || std::abs(n - static_cast<double>(cells)) > 1e-6 * std::max(1.0, n))
                throw input_error(fmt::format("{}[{}] = {} must be a positive whole multiple of {} = {}", r.key_path("size"),
                                              a, size[a], r.key_path("cell_size"), g.h));
              g.cells[a] = static_cast<int>(cells);
            }
          },
          [](const SceneDraft& d, Json& j) {
            const GridGeometry& g = d.scene.grid;
            // cells x h as computed (0.6000000000000001 for 48 x 0.0125): the scene's hash, which a
            // checkpoint carries, is of this text, so rounding it would refuse earlier checkpoints
            // (scene.json shows it rounded: scene_file_json)
            j["size"] = Json::array({g.cells[0] * g.h, g.cells[1] * g.h, g.cells[2] * g.h});
          },
          {.required = true}),
      object<SceneDraft>(
          "terrain", terrain_table, "none (flat grid)", "the bed of a terrain-following grid",
          {.end = [](ObjectReader& terrain, SceneDraft& d) {
             // validates: a graph z_b(x), transitions that fit
             with_key_path(terrain.path() + ".", [&] { (void)TerrainProfile(d.scene.grid.terrain); });
           },
           .present = [](const SceneDraft& d) { return d.scene.grid.has_terrain(); }},
          {}, false),
      // Positions are absolute coordinates: far from 0 a double cannot resolve a step's displacement
      // (at x = 1e15 m the doubles are 0.125 m apart, and a block of 0.02 m cells seeded as one plane).
      check<SceneDraft>([](ObjectReader& r, SceneDraft& d) {
        const GridGeometry& g = d.scene.grid;
        double largest = 0.0;
        for (int a = 0; a < 3; ++a)
          largest = std::max({largest, std::abs(g.origin[a]), std::abs(g.origin[a] + g.cells[a] * g.h)});
        for (const auto& point : g.terrain.points)  // on a terrain grid z = w + z_b(x)
          largest = std::max(largest, std::abs(point[1]) + std::abs(g.origin[2]) + g.cells[2] * g.h);
        const double resolution = std::nextafter(largest, kHuge) - largest;  // the doubles' spacing there
        if (resolution > 1e-6 * g.h)
          throw input_error(fmt::format(
              "{}: coordinates reach {:.6g} m, where doubles are {:.3g} m apart, more than 1e-6 of {} = {}: move "
              "grid.origin (and the bodies) nearer 0",
              r.key_path("origin"), largest, resolution, r.key_path("cell_size"), g.h));
      }),
  }};
}
constexpr auto grid_table = &table_of<SceneDraft, make_grid_table>;

Table<SceneDraft> make_time_table() {
  return {{
      number<SceneDraft>("end", TALUS_AT(scene.end_time), {0.0, kHuge, true}, "simulated end time [s]",
                         {.required = true}),
      number<SceneDraft>("courant", TALUS_AT(scene.courant), {0.0, 1.0, true, true},
                         "α in dt = α h / max(c + \\|v\\|) (Edo & Matsubara 2015, eq. 60)"),
      integer<SceneDraft>("max_steps", TALUS_AT(scene.max_steps), 0, 2000000000,
                          "stop after this many steps (0: no limit)"),
  }};
}
constexpr auto time_table = &table_of<SceneDraft, make_time_table>;

// ---- solver --------------------------------------------------------------------------------------

// MLS smoothing (Edo & Matsubara 2015, eq. 38-46, 54). Body names are resolved once the bodies are read.
Table<SceneDraft> make_smoothing_table() {
  return {{
      custom<SceneDraft>(
          "enabled", "boolean", "true", "", "switch it off without deleting the settings",
          {{"type", "boolean"}, {"default", true}},
          [](ObjectReader& r, SceneDraft& d) { d.scene.smoothing.enabled = r.boolean_or("enabled", true); },
          [](const SceneDraft& d, Json& j) { j["enabled"] = d.scene.smoothing.enabled; }),
      choice<SceneDraft>("basis", TALUS_AT(scene.smoothing.mls.basis),
                         named({MlsBasis::Linear, MlsBasis::Quadratic, MlsBasis::Cubic}),
                         "polynomial basis: 4 / 10 / 20 terms in 3D (2 / 3 / 4 along one axis)"),
      choice<SceneDraft>("variant", TALUS_AT(scene.smoothing.mls.variant),
                         named({MlsVariant::Particle, MlsVariant::Cell, MlsVariant::Reused}),
                         "`particle`: one fit per particle, centred on it (Edo & Matsubara 2015, the reference). "
                         "`cell`: one fit per cell, centred on the cell, evaluated at each of its particles: about "
                         "half the cost at 1 and 2 cells, a different smoothing, and not energy-stable: it fed energy into "
                         "the elastic block between walls (`run` and `check` warn; docs/verification.md, \"MLS, one fit "
                         "per cell\"). `reused`: the particle fit, its weights kept and reused until the material has "
                         "strained by `reuse_strain` since the fit: a step that fits smooths as `particle` would, the steps "
                         "between smooth with the weights of the positions of the last fit; costs "
                         "memory for the weights (12 B per neighbour: about 0.4 kB a particle at 1 cell, 3 kB at 2) "
                         "(docs/verification.md, \"MLS, the particle fit's weights reused\")"),
      number<SceneDraft>("radius_factor", TALUS_AT(scene.smoothing.mls.radius_factor), {0.5, 8.0},
                         "support radius h = factor × cell size (eq. 39). Above 2.5, `run` and `check` warn: 3 cells "
                         "and more went unstable on the benchmarks (docs/verification.md, \"MLS radius\")"),
      choice<SceneDraft>(
          "axes", TALUS_AT(scene.smoothing.mls.axes),
          std::vector<std::pair<std::string, std::array<bool, 3>>>{{"xyz", {true, true, true}},
                                                                   {"xy", {true, true, false}},
                                                                   {"xz", {true, false, true}},
                                                                   {"yz", {false, true, true}},
                                                                   {"x", {true, false, false}},
                                                                   {"y", {false, true, false}},
                                                                   {"z", {false, false, true}}},
          "the axes the basis spans; leave out an axis along which a body has too few particle layers for the basis "
          "(a thin bar with 2 layers across cannot fit a quadratic across: use `\"x\"`, Edo & Matsubara's 1D fit). "
          "Neighbours are still taken within the 3D radius"),
      number<SceneDraft>("reuse_strain", TALUS_AT(scene.smoothing.mls.reuse_strain), {0.0, 1.0},
                         "`reused` only: the fits are redone once the sum, over the steps since the fit, of each step's "
                         "largest strain increment (Frobenius norm, before smoothing) exceeds this; 0 fits again after every step "
                         "that strains the material (the `particle` result). At 1e-2 a tenth of a DP collapse's steps fit "
                         "and its front moved by 0.1 cell; at 1e-3 most steps fit, which is no faster than `particle`"),
      number<SceneDraft>("min_rcond", TALUS_AT(scene.smoothing.mls.min_rcond), {0.0, 1.0, true, true},
                         "guard: a particle whose moment matrix A has a reciprocal condition number (1-norm estimate) "
                         "below this, or fewer neighbours than basis terms, keeps its own increment and is counted "
                         "(`Solver::unsmoothed_total`)"),
      custom<SceneDraft>(
          "bodies", "[names]", "every body", "names of `bodies`",
          "the bodies smoothed; neighbours are always taken from the particle's own body only",
          {{"type", "array"}, {"items", {{"type", "string"}}}, {"minItems", 1}},
          [](ObjectReader& r, SceneDraft& d) {
            if (!r.has("bodies")) return;
            const Json& b = r.raw("bodies");
            if (!b.is_array() || b.empty())
              throw input_error(
                  fmt::format("{} must be a non-empty array of body names, got {}", r.key_path("bodies"), b.dump()));
            for (std::size_t i = 0; i < b.size(); ++i) {
              if (!b[i].is_string())
                throw input_error(fmt::format("{}[{}] must be a body name (string), got {}", r.key_path("bodies"), i,
                                              b[i].dump()));
              d.smoothing_bodies.push_back(b[i].get<std::string>());
            }
          },
          [](const SceneDraft& d, Json& j) {
            const Scene& s = d.scene;
            Json names = Json::array();
            for (std::size_t b = 0; b < s.bodies.size(); ++b)
              if (s.smoothing.bodies.empty() ||
                  std::find(s.smoothing.bodies.begin(), s.smoothing.bodies.end(), int(b)) != s.smoothing.bodies.end())
                names.push_back(s.bodies[b].name);
            j["bodies"] = names;
          }),
      // The neighbour search walks the sort's cells, which on a terrain grid are cells in w = z - z_b(x):
      // a ball in (x, y, z) is not a ball of those cells where the bed slopes. The grid is read above.
      check<SceneDraft>([](ObjectReader&, SceneDraft& d) {
        if (d.scene.smoothing.enabled && d.scene.grid.has_terrain())
          throw input_error(
              "solver.smoothing cannot run on a terrain grid (grid.terrain is set: the MLS neighbour search works in the "
              "bed-following cells): remove it or set solver.smoothing.enabled = false");
      }),
  }};
}
constexpr auto smoothing_table = &table_of<SceneDraft, make_smoothing_table>;

Table<SceneDraft> make_solver_table() {
  return {{
      choice<SceneDraft>("scheme", TALUS_AT(scene.scheme),
                         named({SchemeKind::Musl, SchemeKind::Usl, SchemeKind::Usf, SchemeKind::Usavg}),
                         "update scheme: MUSL (Edo & Matsubara 2015, eq. 47–56), USL (no remap), USF (stress first, "
                         "Bardenhagen 2002), USAVG (half step each, Nairn 2003; Abe, Johansson & Konagai 2005, "
                         "sec. 4(1)); docs/theory.md"),
      choice<SceneDraft>("shape", TALUS_AT(scene.shape),
                         named({ShapeKind::Linear, ShapeKind::UGimp, ShapeKind::CpGimp, ShapeKind::BSpline2}),
                         "shape functions: linear MPM (Edo & Matsubara 2015, eq. 28–29), uGIMP (eq. 30–31, 59), "
                         "cpGIMP (eq. 30–31, 57–58), quadratic B-spline; docs/theory.md"),
      integer<SceneDraft>("sort_interval", TALUS_AT(scene.sort_interval), 1, 1000000,
                          "re-sort particles by cell at least this often (also when one leaves its block's slack, and with MLS smoothing when one may have moved a quarter cell since the sort)"),
      integer<SceneDraft>("block_cells", TALUS_AT(scene.block_cells), 0, 64,
                          "edge of the colour blocks in cells; 0 = automatic (4 for linear, 8 for the others). Smaller "
                          "blocks share small scenes better among many threads (docs/performance.md \"Scaling\"); "
                          "results stay the same for any thread count but differ at round-off from another block size",
                          {.allowed = "0, or 3..64 (linear), 5..64 (other shapes)"}),
      // The smallest block: 2 x one cell of slack + the support's reach (linear: 0 below, 1 above;
      // the others 1 and 2). The shape is read above, so the message can name it.
      check<SceneDraft>([](ObjectReader& r, SceneDraft& d) {
        const Scene& s = d.scene;
        const ShapeReach reach = shape_reach(s.shape);
        const int smallest_block = 2 + reach.low + reach.high;
        if (s.block_cells != 0 && s.block_cells < smallest_block)
          throw input_error(
              fmt::format("{} = {}: must be 0 (automatic) or {}..64 for the {} shape (two cells of slack + its reach)",
                          r.key_path("block_cells"), s.block_cells, smallest_block, to_string(s.shape)));
      }),
      choice<SceneDraft>("scatter", TALUS_AT(scene.scatter), named({ScatterOrder::ColourPasses, ScatterOrder::BlockBuffers}),
                         "how P2G and the MUSL remap add the particles into the nodes without races: colour_passes (8 "
                         "passes over the colour blocks, a barrier after each) or block_buffers (every block into node "
                         "records of its own in one pass, then the boxes added tile by tile; more work per particle, "
                         "fewer and larger parallel loops: for small scenes on many threads, docs/performance.md "
                         "\"Scaling\"). Both give the same results for any thread count; they differ from each other at "
                         "round-off. block_buffers does not support periodic boundaries"),
      number<SceneDraft>("gravity_ramp_time", TALUS_AT(scene.gravity_ramp_time), {0.0, kHuge},
                         "gravity grows linearly from 0 to its full value over this time (0: applied at once); for "
                         "quasi-static loading such as the column benchmark. The energy budget's gravity term is the "
                         "full g's potential; the part of it the ramp withholds is its own term, gravity_ramp",
                         {.unit = "s"}),
      number<SceneDraft>("pic_fraction", TALUS_AT(scene.pic_fraction), {0.0, 1.0},
                         "the PIC share β of the G2P velocity update, v_p = (1 − β)(v_p + Σ N Δv) + β Σ N v^L (0: pure "
                         "FLIP, Edo & Matsubara 2015, eq. 50; 1: pure PIC). A small share damps the grid-scale velocity "
                         "noise that otherwise keeps a granular deposit jittering (the flume uses 0.01, docs/flume.md); "
                         "the kinetic energy it removes is the `damping` column of energy.csv, so the budget still closes"),
      object<SceneDraft>(
          "smoothing", smoothing_table, "absent (off)",
          "MLS smoothing of the strain increments between the strain pass and the material update (Edo & Matsubara "
          "2015, eq. 38–46, 54; docs/theory.md \"MLS strain smoothing\"). Present = on unless `enabled` is false. Not "
          "on a terrain grid or with periodic faces (the neighbour search works in the sort's cells). Costly: on one "
          "core the per-particle fit took 56-60% of the step at `radius_factor` 1 and 82-86% at 2 (1 M-particle "
          "B-spline column; docs/performance.md \"Why the particle fit stays above its target\"); `variant` "
          "`reused` took 24% in the steps that reuse its weights (1 cell) and ran a flowing collapse 1.4-2.1x "
          "faster (docs/performance.md \"MLS, the particle fit's weights reused\")",
          {.present = [](const SceneDraft&) { return true; }}),
  }};
}
constexpr auto solver_table = &table_of<SceneDraft, make_solver_table>;

// ---- materials -----------------------------------------------------------------------------------

// Drucker-Prager constants (Abe, Johansson & Konagai 2005, eq. 23-25, Table 2). Their ranges are
// checked by the DruckerPrager constructor (the material layer), which names the key path.
Fields<DruckerPragerParameters> drucker_prager_strength_fields() {
  using P = DruckerPragerParameters;
  return {
      number<P>("friction_angle", TALUS_AT(friction_angle_deg), {0.0, 90.0, true, true}, "internal friction angle φ",
                {.unit = "°", .required = true, .domain_checked = true}),
      number<P>("dilatancy_angle", TALUS_AT(dilatancy_angle_deg), {0.0, 90.0, false, true},
                "dilatancy angle ψ (ψ = φ: associated flow)", {.unit = "°", .allowed = "[0, φ]", .domain_checked = true}),
      number<P>("cohesion", TALUS_AT(cohesion), {0.0, kHuge}, "c", {.unit = "Pa", .domain_checked = true}),
      number<P>("hardening_modulus", TALUS_AT(hardening_modulus), {0.0, kHuge}, "H = dk/dε_p (0: perfect plasticity)",
                {.unit = "Pa", .domain_checked = true}),
      number<P>("kinematic_fraction", TALUS_AT(kinematic_fraction), {0.0, 1.0},
                "Prager mixing: share of H that is kinematic (Abe, Johansson & Konagai's 0.8 isotropic share = 0.2)",
                {.domain_checked = true}),
      custom<P>(
          "tension_cutoff", "number [Pa]", "`\"apex\"`", "≥ 0, or `\"apex\"`",
          "largest mean stress (tension positive); `\"apex\"`: the cone's apex is the only tension limit",
          {{"oneOf", Json::array({{{"type", "number"}, {"minimum", 0}}, {{"const", "apex"}}})}, {"default", "apex"}},
          [](ObjectReader& r, P& p) {
            if (!r.has("tension_cutoff")) return;
            const Json& j = r.raw("tension_cutoff");
            if (j.is_string()) {
              if (j.get<std::string>() != "apex")
                throw input_error(fmt::format("{} = {} is not \"apex\" or a mean stress >= 0 (Pa)",
                                              r.key_path("tension_cutoff"), j.dump()));
              p.tension_cutoff = std::numeric_limits<double>::infinity();
            } else {
              p.tension_cutoff = r.number("tension_cutoff", -kHuge, kHuge);  // range: the DruckerPrager check
            }
          },
          [](const P& p, Json& j) {
            if (std::isfinite(p.tension_cutoff)) j["tension_cutoff"] = p.tension_cutoff;
          }),
      choice<P>("cone", TALUS_AT(cone),
                named({ConeFit::PlaneStrain, ConeFit::Compression, ConeFit::Extension, ConeFit::Inscribed}),
                "how the cone matches Mohr–Coulomb"),
  };
}

// μ(I) constants (Jop, Forterre & Pouliquen 2006, the friction law and the inertial number;
// docs/mu-i.md). Defaults: their glass beads (MuIParameters). The ranges, μ2 > μs among them, are
// checked by the MuI constructor (the material layer), which names the key.
Fields<MuIParameters> mu_i_fields() {
  using P = MuIParameters;
  return {
      number<P>("mu_s", TALUS_AT(mu_s), {0.0, kHuge}, "static friction coefficient μs (glass beads, Jop et al. 2006: tan 20.9°)",
                {.domain_checked = true}),
      number<P>("mu_2", TALUS_AT(mu_2), {0.0, kHuge, true}, "limiting friction coefficient μ2 as I → ∞ (glass beads: tan 32.76°)",
                {.allowed = "> μs", .domain_checked = true}),
      number<P>("i0", TALUS_AT(i0), {0.0, kHuge, true}, "I0 of μ(I) = μs + (μ2 − μs)/(1 + I0/I)",
                {.domain_checked = true}),
      number<P>("grain_diameter", TALUS_AT(grain_diameter), {0.0, kHuge, true}, "d in I = γ̇ᵖ d / √(p/ρs), in metres (in a scene, above 0.05 m `run` and `check` warn: millimetres?)",
                {.unit = "m", .domain_checked = true}),
      number<P>("grain_density", TALUS_AT(grain_density), {0.0, kHuge, true}, "ρs, the density of the grains (not of the packing: that is `density`, which may not exceed it)",
                {.unit = "kg/m³", .domain_checked = true}),
  };
}

Table<MaterialSpec> make_material_table() {
  // The models, the default first; a model's keys are the fields with .when = {its name}.
  const auto models = named({MaterialModel::LinearElastic, MaterialModel::DruckerPrager, MaterialModel::MuI});
  using M = MaterialSpec;
  const std::vector<std::string> dp = {"drucker_prager"};
  const std::vector<std::string> mu_i = {"mu_i"};
  const std::vector<std::string> granular = {"drucker_prager", "mu_i"};
  const std::vector<std::string> elastic = {"linear_elastic"};
  Table<M> t;
  t.selector = "model";
  for (const auto& [word, model] : models) t.values.push_back(word);
  t.selected = [](const M& m) { return std::string(to_string(m.model)); };
  t.fields = join<M>({
      {choice<M>("model", TALUS_AT(model),
                 models,
                 "constitutive model (Drucker–Prager: Abe, Johansson & Konagai 2005, eq. 23–25; docs/drucker-prager.md; "
                 "μ(I): Jop, Forterre & Pouliquen 2006 in the form of Dunatunga & Kamrin 2015, docs/mu-i.md)"),
       number<M>("density", TALUS_AT(density), {0.0, kHuge, true}, "initial density [kg/m³] (below 100 or above 25000, with gravity of 1 to 50 m/s², `run` and `check` warn: "
                 "g/cm³?)",
                 {.required = true}),
       number<M>("young", TALUS_AT(elastic.young), {0.0, kHuge, true}, "Young's modulus E [Pa] (`run` and `check` warn where a body's self-weight strain ρ g H / E, H its "
                 "extent along gravity, passes 0.1)",
                 {.required = true}),
       number<M>("poisson", TALUS_AT(elastic.poisson), {-1.0, 0.5, true, true}, "Poisson's ratio ν",
                 {.required = true, .when = elastic}),
       number<M>("poisson", TALUS_AT(elastic.poisson), {0.0, 0.5, false, true}, "Poisson's ratio ν",
                 {.required = true, .when = granular})},
      lift<M, DruckerPragerParameters>(drucker_prager_strength_fields(), TALUS_AT(drucker_prager), dp),
      {check<M>(
           [](ObjectReader& r, M& m) {
             m.drucker_prager.young = m.elastic.young;
             m.drucker_prager.poisson = m.elastic.poisson;
             with_key_path(r.path() + ".", [&] { (void)DruckerPrager(m.drucker_prager); });
           },
           dp)},
      lift<M, MuIParameters>(mu_i_fields(), TALUS_AT(mu_i), mu_i),
      {check<M>(
           [](ObjectReader& r, M& m) {
             m.mu_i.young = m.elastic.young;
             m.mu_i.poisson = m.elastic.poisson;
             with_key_path(r.path() + ".", [&] { (void)MuI(m.mu_i); });
             // The solid fraction density / grain_density sets the Bagnold scaling (docs/mu-i.md); above 1
             // it describes no packing (a density of 1600 with grains of 1000 was accepted).
             if (m.density > m.mu_i.grain_density)
               throw input_error(fmt::format("{}.density = {} is above grain_density = {}: a packing cannot be denser than "
                                             "its grains (solid fraction density / grain_density <= 1)",
                                             r.path(), m.density, m.mu_i.grain_density));
           },
           mu_i),
       number<M>("flowing_plastic_strain", TALUS_AT(granular.flowing_plastic_strain), {0.0, kHuge},
                 "ε_p beyond which a particle counts as flowing", {.when = dp}),
       custom<M>(
           "flowing_dilatancy_angle", "number [°]", "0", "[0, φ]",
           "ψ used once flowing (Abe, Johansson & Konagai 2005: \"dilatancy 0 once flow starts\")",
           {{"type", "number"}, {"minimum", 0}, {"exclusiveMaximum", 90}, {"default", 0}},
           [](ObjectReader& r, M& m) {
             double& v = m.granular.flowing_dilatancy_angle_deg;
             v = r.number_or("flowing_dilatancy_angle", v, 0.0, m.drucker_prager.friction_angle_deg);
           },
           [](const M& m, Json& j) { j["flowing_dilatancy_angle"] = m.granular.flowing_dilatancy_angle_deg; },
           {.when = dp}),
       custom<M>(
           "separation_volume_ratio", "number", "1.5", "> 1, or 0 (off)",
           "V/V0 beyond which a particle is separated: stress-free, plastic state reset; below ratio V0 it "
           "carries stress again, so 1.05 lets a loosened deposit re-compact (docs/flume.md)",
           {{"type", "number"},
            {"anyOf", Json::array({{{"const", 0}}, {{"exclusiveMinimum", 1}}})},
            {"default", GranularOptions{}.separation_volume_ratio}},
           [](ObjectReader& r, M& m) {
             double& v = m.granular.separation_volume_ratio;
             v = r.number_or("separation_volume_ratio", v, 0.0, kHuge);
             if (v != 0.0 && v <= 1.0)
               throw input_error(fmt::format("{} = {} is outside the allowed range (1, inf), or 0 to disable",
                                             r.key_path("separation_volume_ratio"), v));
           },
           [](const M& m, Json& j) { j["separation_volume_ratio"] = m.granular.separation_volume_ratio; },
           {.when = granular})},
  });
  return t;
}
constexpr auto material_table = &table_of<MaterialSpec, make_material_table>;

// ---- bodies --------------------------------------------------------------------------------------

/// A body while it is read: it checks its box against the scene's grid and names its material.
struct BodyDraft {
  BodySpec body;
  const SceneDraft* scene = nullptr;
};

// The body's bounding box must lie in the grid. (On a terrain grid the third axis is w = z - z_b(x):
// the terrain branch maps this check.)
void check_inside_grid(const BodySpec& b, const std::string& path, const Scene& s) {
  for (int d = 0; d < 3; ++d) {
    // A physical body on a terrain grid is checked against the bed when seeding (seeding.cpp): the
    // grid's z range depends on x there.
    if (d == 2 && s.grid.has_terrain() && b.frame == BoxFrame::Physical) continue;
    const double lo = s.grid.origin[d];
    const double hi = lo + s.grid.cells[d] * s.grid.h;
    // (round-off of the grid's extent, the same margin on both sides: relative to the lower bound
    // alone it was none at an origin of 0, where a min of -1e-17 was refused)
    const double margin = 1e-12 * (std::abs(lo) + std::abs(hi));
    const bool below = b.box_min[d] < lo - margin, above = b.box_max[d] > hi + margin;
    if (!below && !above) continue;
    // (named by the key at fault: a box's min[d] or max[d], the third of a terrain-frame box being w)
    const bool wholly = b.box_max[d] < lo - margin || b.box_min[d] > hi + margin;
    const std::string extent = fmt::format("[{}, {}] along axis {}", b.box_min[d], b.box_max[d], d);
    const std::string grid_range = fmt::format("[{:.12g}, {:.12g}]", lo, hi);
    if (b.shape != BodyShapeKind::Box)
      throw input_error(fmt::format("{} {} lies {}outside the grid {}", path, extent, wholly ? "wholly " : "partly ",
                                    grid_range));
    const char* axis = d == 0 ? "x" : d == 1 ? "y" : b.frame == BoxFrame::Terrain ? "w, the height above the bed" : "z";
    if (below && above)
      throw input_error(fmt::format("{0}.min[{1}] = {2} and {0}.max[{1}] = {3} ({4}) lie outside the grid {5}: the box "
                                    "is wider than the grid along axis {1}",
                                    path, d, b.box_min[d], b.box_max[d], axis, grid_range));
    throw input_error(fmt::format("{}.{}[{}] = {} ({}) lies outside the grid {}: the box {} lies {}outside it", path,
                                  below ? "min" : "max", d, below ? b.box_min[d] : b.box_max[d], axis, grid_range,
                                  extent, wholly ? "wholly " : "partly "));
  }
}

Table<BodyDraft> make_box_table() {
  return {{
      vec3<BodyDraft>("min", TALUS_AT(body.box_min), "lower corner of the box filled with particles",
                      {.required = true, .allowed = "inside the grid, min < max"}),
      vec3<BodyDraft>("max", TALUS_AT(body.box_max), "upper corner of the box filled with particles",
                      {.required = true, .allowed = "inside the grid, min < max"}),
      custom<BodyDraft>(
          "frame", "string", "`\"physical\"`", "`physical`, `terrain` (needs `grid.terrain`)",
          "`terrain`: the box's third coordinate is w, the height above the bed: a layer of uniform vertical thickness "
          "over the bed, made of whole isoparametric cells (a block on a slope is a parallelogram with vertical sides). "
          "`physical` on a terrain grid: the bed clips the part of the box below it (a warning gives the share lost)",
          {{"type", "string"}, {"enum", {"physical", "terrain"}}, {"default", "physical"}},
          [](ObjectReader& r, BodyDraft& d) {
            if (!r.has("frame")) return;
            const bool terrain = r.choice("frame", "physical", {"physical", "terrain"}) == "terrain";
            // Only the terrain frame needs a bed; "physical", the default, written out is the flat grid's
            // own frame (it was refused there as if it were "terrain").
            if (terrain && !d.scene->scene.grid.has_terrain())
              throw input_error(fmt::format("{} = \"terrain\" needs grid.terrain (on a flat grid z is the height "
                                            "above the floor: leave frame out, or write \"physical\")",
                                            r.key_path("frame")));
            d.body.frame = terrain ? BoxFrame::Terrain : BoxFrame::Physical;
          },
          [](const BodyDraft& d, Json& j) {
            if (d.body.frame == BoxFrame::Terrain) j["frame"] = "terrain";
          }),
      check<BodyDraft>([](ObjectReader& r, BodyDraft& d) {
        const BodySpec& b = d.body;
        for (int a = 0; a < 3; ++a)
          if (!(b.box_min[a] < b.box_max[a]))
            throw input_error(
                fmt::format("{}.min[{}] = {} must be below max[{}] = {}", r.path(), a, b.box_min[a], a, b.box_max[a]));
        check_inside_grid(b, r.path(), d.scene->scene);
      }),
  }};
}
constexpr auto box_table = &table_of<BodyDraft, make_box_table>;

// "prism": {"points": [[x, z], ...], "y": [y0, y1]}: a simple polygon in the x-z plane, extruded.
Table<BodyDraft> make_prism_table() {
  return {{
      custom<BodyDraft>(
          "points", "[[x, z], ...]", "required with `prism`",
          "≥ 3 points, a simple polygon (no crossing or touching edges, non-zero area), inside the grid",
          "the cross-section in the x-z plane of a prism body (e.g. the sand wedge behind a gate)",
          point_pairs_schema(3),
          [](ObjectReader& r, BodyDraft& d) {
            BodySpec& b = d.body;
            const Json& pts = r.raw("points");
            const std::string points_path = r.key_path("points");
            if (!pts.is_array() || pts.size() < 3)
              throw input_error(fmt::format("{} must be an array of at least 3 [x, z] points, got {}", points_path,
                                            pts.is_array() ? fmt::format("{} points", pts.size()) : pts.dump()));
            if (pts.size() > 10000)
              throw input_error(fmt::format("{} has {} points; at most 10000", points_path, pts.size()));
            b.prism.points = read_point_pairs(pts, points_path);
            // GIS tools write a ring closed by its first point: the polygon closes itself here
            if (b.prism.points.front() == b.prism.points.back())
              throw input_error(fmt::format("{}: the last point, [{}], repeats the first; leave it out (the polygon "
                                            "closes itself from the last point to the first)",
                                            points_path, fmt::format("{}, {}", b.prism.points.back()[0], b.prism.points.back()[1])));
            const auto crossing = polygon_crossing_edges(b.prism.points);
            if (crossing[0] >= 0)
              throw input_error(fmt::format(
                  "{} is not a simple polygon: edge {} (points {} to {}) touches edge {} (points {} to {})", points_path,
                  crossing[0], crossing[0], (crossing[0] + 1) % pts.size(), crossing[1], crossing[1],
                  (crossing[1] + 1) % pts.size()));
            if (polygon_signed_area(b.prism.points) == 0.0)
              throw input_error(fmt::format("{} encloses no area", points_path));
          },
          [](const BodyDraft& d, Json& j) { j["points"] = point_pairs_json(d.body.prism.points); },
          {.required = true, .fallback = "required with `prism`"}),
      custom<BodyDraft>(
          "y", "[y0, y1]", "required with `prism`", "y0 < y1, inside the grid", "the prism's extent across y",
          {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 2}, {"maxItems", 2}},
          [](ObjectReader& r, BodyDraft& d) {
            PrismSpec& p = d.body.prism;
            const Json& y = r.raw("y");
            if (!y.is_array() || y.size() != 2)
              throw input_error(fmt::format("{} must be [y0, y1] with y0 < y1, got {}", r.key_path("y"), y.dump()));
            p.y0 = ObjectReader::check_number(y[0], r.key_path("y") + "[0]", -kHuge, kHuge, false, false);
            p.y1 = ObjectReader::check_number(y[1], r.key_path("y") + "[1]", -kHuge, kHuge, false, false);
            if (!(p.y0 < p.y1))
              throw input_error(fmt::format("{} = [{}, {}] must have y0 < y1", r.key_path("y"), p.y0, p.y1));
          },
          [](const BodyDraft& d, Json& j) { j["y"] = Json::array({d.body.prism.y0, d.body.prism.y1}); },
          {.required = true, .fallback = "required with `prism`"}),
      check<BodyDraft>([](ObjectReader&, BodyDraft& d) {
        BodySpec& b = d.body;
        b.box_min = Vec3(kHuge, b.prism.y0, kHuge);
        b.box_max = Vec3(-kHuge, b.prism.y1, -kHuge);
        for (const auto& p : b.prism.points) {
          b.box_min[0] = std::min(b.box_min[0], p[0]);
          b.box_max[0] = std::max(b.box_max[0], p[0]);
          b.box_min[2] = std::min(b.box_min[2], p[1]);
          b.box_max[2] = std::max(b.box_max[2], p[1]);
        }
      }),
  }};
}
constexpr auto prism_table = &table_of<BodyDraft, make_prism_table>;

Table<BodyDraft> make_body_table() {
  return {{
      string<BodyDraft>("name", TALUS_AT(body.name), "body name (shown in diagnostics)", {.required = true}),
      custom<BodyDraft>(
          "material", "string", "required", "a key of `materials`", "the body's material", {{"type", "string"}},
          [](ObjectReader& r, BodyDraft& d) {
            const std::string material = r.string("material");
            const auto& materials = d.scene->material_index;
            auto it = materials.find(material);
            if (it == materials.end()) {
              std::string known;
              for (const auto& [k, v] : materials) known += (known.empty() ? "" : ", ") + k;
              throw input_error(
                  fmt::format("{} = \"{}\" names no material (defined: {})", r.key_path("material"), material, known));
            }
            d.body.material = it->second;
          },
          [](const BodyDraft& d, Json& j) { j["material"] = d.scene->scene.materials[d.body.material].name; },
          {.required = true}),
      check<BodyDraft>([](ObjectReader& r, BodyDraft&) {
        if (r.has("box") == r.has("prism"))
          throw input_error(fmt::format("{} needs exactly one shape: \"box\" or \"prism\"", r.path()));
      }),
      object<BodyDraft>("box", box_table, "one of `box`, `prism`", "box filled with particles",
                        {.present = [](const BodyDraft& d) { return d.body.shape == BodyShapeKind::Box; }}),
      object<BodyDraft>(
          "prism", prism_table, "one of `box`, `prism`", "a prism body: a polygon in the x-z plane extruded over y",
          {.begin = [](BodyDraft& d) { d.body.shape = BodyShapeKind::Prism; },
           .end = [](ObjectReader& prism, BodyDraft& d) { check_inside_grid(d.body, prism.path(), d.scene->scene); },
           .present = [](const BodyDraft& d) { return d.body.shape == BodyShapeKind::Prism; }}),
      integer<BodyDraft>("particles_per_cell", TALUS_AT(body.particles_per_cell), 1, 8, "n: n×n×n particles per cell"),
      vec3<BodyDraft>("velocity", TALUS_AT(body.velocity), "initial velocity", {.type = "[vx, vy, vz]"}),
  }};
}
constexpr auto body_table = &table_of<BodyDraft, make_body_table>;

// ---- boundaries, output, guards, diagnostics ----------------------------------------------------

WallType wall_type(const std::string& t, const std::string& at) {
  if (t == "open") return WallType::Open;
  if (t == "slip") return WallType::Slip;
  if (t == "fixed") return WallType::Fixed;
  if (t == "friction") return WallType::Friction;
  if (t == "periodic") return WallType::Periodic;
  throw input_error(fmt::format("{} = \"{}\" is not one of: open, slip, fixed, friction, periodic", at, t));
}

WallSpec read_wall(const Json& j, const std::string& path) {
  WallSpec w;
  if (j.is_string()) {
    w.type = wall_type(j.get<std::string>(), path);
    if (w.type == WallType::Friction)
      throw input_error(fmt::format("{} = \"friction\" needs an object with friction_coefficient", path));
    return w;
  }
  // (a number said "must be an object", as if a string were not allowed)
  if (!j.is_object())
    throw input_error(fmt::format(
        "{} must be a string (open, slip, fixed, periodic) or an object with type (friction needs one), got {}", path,
        j.type_name()));
  ObjectReader r(j, path);
  // (a misspelt key first: friction_coeff was reported as the missing friction_coefficient)
  r.refuse_unknown({"type", "friction_coefficient"});
  w.type = wall_type(r.string("type"), r.key_path("type"));
  if (w.type == WallType::Friction) w.friction_coefficient = r.number("friction_coefficient", 0.0, 100.0);
  // (finish() said only "unknown key ...friction_coefficient (keys read here: type)")
  if (w.type != WallType::Friction && r.has("friction_coefficient"))
    throw input_error(fmt::format("{} belongs to \"type\": \"friction\" faces; this face is \"{}\": make it "
                                  "\"friction\", or leave friction_coefficient out",
                                  r.key_path("friction_coefficient"), r.string("type")));
  r.finish();
  return w;
}

// Periodic faces (docs/theory.md "Periodic boundaries"): x and y only, in pairs, on a flat grid,
// without MLS smoothing (its neighbour search does not wrap), and with a cell count the colour
// blocks tile as 1 or an even number of blocks (CellSort::periodic_blocks_fit). Sets the grid's
// periodic axes.
void check_periodic_faces(ObjectReader& r, SceneDraft& d) {
  Scene& s = d.scene;
  for (int a = 0; a < 3; ++a) {
    const bool lower = s.walls[a][0].type == WallType::Periodic, upper = s.walls[a][1].type == WallType::Periodic;
    if (!lower && !upper) continue;
    const char* face = face_name(a, lower ? 0 : 1);
    const std::string at = r.key_path(face);
    if (a == 2) throw input_error(fmt::format("{} = \"periodic\": only the x and y faces can be periodic", at));
    if (lower != upper) {
      const char* other = face_name(a, lower ? 1 : 0);
      throw input_error(fmt::format("{} = \"{}\": must be \"periodic\" like {} (periodic faces come in pairs)",
                                    r.key_path(other), to_string(s.walls[a][lower ? 1 : 0].type), at));
    }
    // Along y the bed would repeat, but no test covers periodic faces on a terrain grid: refused, as documented.
    if (s.grid.has_terrain())
      throw input_error(fmt::format("{} = \"periodic\" needs a flat grid: grid.terrain is set ({})", at,
                                    a == 0 ? "a bed profile does not repeat" : "periodic faces are not verified on a terrain grid"));
    if (s.scatter == ScatterOrder::BlockBuffers)
      throw input_error(fmt::format(
          "{} = \"periodic\" cannot run with solver.scatter = \"block_buffers\" (the boxes do not wrap): use "
          "\"colour_passes\"",
          at));
    if (s.smoothing.enabled)
      throw input_error(fmt::format(
          "{} = \"periodic\" cannot run with solver.smoothing (the MLS neighbour search does not wrap): remove it or set "
          "solver.smoothing.enabled = false",
          at));
    const int edge = colour_block_edge(s);
    const int cells = s.grid.cells[a];
    if (!CellSort::periodic_blocks_fit(cells, edge)) {
      int suggestion = 2 * edge;
      while (suggestion < cells) suggestion += 2 * edge;
      throw input_error(fmt::format(
          "grid.cells[{}] = {} with periodic {} faces: must be {} or a multiple of {} (1 or an even number of colour "
          "blocks of {} cells, solver.block_cells{}), e.g. {}",
          a, cells, "xy"[a], edge, 2 * edge, edge, s.block_cells == 0 ? " automatic for this shape" : "", suggestion));
    }
    s.grid.periodic[a] = true;
  }
}

Table<SceneDraft> make_boundaries_table() {
  const Json wall_schema = {
      {"oneOf",
       Json::array({{{"type", "string"}, {"enum", {"open", "slip", "fixed", "periodic"}}},
                    {{"type", "object"},
                     {"properties",
                      {{"type", {{"type", "string"}, {"enum", {"open", "slip", "fixed", "friction"}}}},
                       {"friction_coefficient", {{"type", "number"}, {"minimum", 0}, {"maximum", 100}}}}},
                     {"required", {"type"}},
                     {"additionalProperties", false}}})},
      {"default", "slip"}};
  Table<SceneDraft> t;
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      auto f = custom<SceneDraft>(
          face_name(a, side), "string or object", "`\"slip\"`", "see below", "faces `x-`, `x+`, `y-`, `y+`, `z-`, `z+`",
          wall_schema,
          [a, side](ObjectReader& r, SceneDraft& d) {
            const char* face = face_name(a, side);
            if (r.has(face)) d.scene.walls[a][side] = read_wall(r.raw(face), r.key_path(face));
          },
          [a, side](const SceneDraft& d, Json& j) {
            const WallSpec& w = d.scene.walls[a][side];
            if (w.type == WallType::Friction)
              j[face_name(a, side)] = {{"type", "friction"}, {"friction_coefficient", w.friction_coefficient}};
            else
              j[face_name(a, side)] = to_string(w.type);
          });
      f.info.doc_key = "<face>";
      f.info.row = a == 0 && side == 0;  // one docs row for the six faces
      t.fields.push_back(std::move(f));
    }
  t.fields.push_back(check<SceneDraft>(check_periodic_faces));
  return t;
}
constexpr auto boundaries_table = &table_of<SceneDraft, make_boundaries_table>;

Table<SceneDraft> make_output_table() {
  return {{
      number<SceneDraft>("frame_interval", TALUS_AT(scene.output.frame_interval), {0.0, kHuge},
                         "seconds between particle frames (0: first and last only)"),
      number<SceneDraft>("history_interval", TALUS_AT(scene.output.history_interval), {0.0, kHuge},
                         "seconds between energy rows (0: every step)"),
      choice<SceneDraft>("compression", TALUS_AT(scene.output.compress),
                         std::vector<std::pair<std::string, bool>>{{"lz4", true}, {"none", false}},
                         "compression inside the .vtu files"),
      number<SceneDraft>("checkpoint_interval", TALUS_AT(scene.output.checkpoint_interval), {0.0, kHuge},
                         "seconds between checkpoints (`checkpoint.h5`, 0: none; SIGINT/SIGTERM and instabilities still "
                         "write one); resume with `talus run SCENE --restart FILE` (docs/reliability.md)"),
      boolean<SceneDraft>("energy_gap_terms", TALUS_AT(scene.output.energy_gap_terms),
                          "also write, in energy.csv, the work done on the grid's motion by its stresses, walls and "
                          "gravity and the kinetic energy lost between grid and particles: what the budget's gap is "
                          "made of (docs/theory.md, \"Where the budget's gap comes from\")"),
  }};
}
constexpr auto output_table = &table_of<SceneDraft, make_output_table>;

// Instability guards (docs/reliability.md).
Table<SceneDraft> make_guards_table() {
  return {{
      number<SceneDraft>("max_step_displacement", TALUS_AT(scene.guards.max_step_displacement), {0.0, 2.0, true},
                         "cells a particle may move in one step; more stops the run as a CFL breach"),
      number<SceneDraft>("energy_growth_factor", TALUS_AT(scene.guards.energy_growth_factor), {0.0, kHuge, true},
                         "stop when the total energy grew by more than this times the energy available (initial "
                         "kinetic + strain + potential released)"),
      number<SceneDraft>("energy_warning_factor", TALUS_AT(scene.guards.energy_warning_factor), {0.0, kHuge},
                         "warn once when the total energy grew by more than this times the energy available: the "
                         "scheme is creating energy, short of the stop (0: off)"),
      number<SceneDraft>("min_volume_ratio", TALUS_AT(scene.guards.min_volume_ratio), {0.0, 1.0, false, true},
                         "stop when a particle's volume falls below this fraction of its seeded volume (mass / "
                         "material density): compression no granular or elastic body survives (0: off)"),
      integer<SceneDraft>("snapshot_interval", TALUS_AT(scene.guards.snapshot_interval), 0, 1000000,
                          "steps between in-memory copies of the last good state, written as a frame and checkpoint "
                          "when a guard trips (0: none)"),
  }};
}
constexpr auto guards_table = &table_of<SceneDraft, make_guards_table>;

/// An optional number whose absence means something (RunoutSpec::has_gate, has_runout_plane).
Field<SceneDraft> present_number(const char* key, double RunoutSpec::*value, bool RunoutSpec::*given,
                                 const std::string& fallback, const std::string& doc) {
  return custom<SceneDraft>(
      key, "number [m]", fallback, "finite", doc, {{"type", "number"}},
      [key, value, given](ObjectReader& r, SceneDraft& d) {
        RunoutSpec& rs = d.scene.runout;
        rs.*given = r.has(key);
        rs.*value = r.number_or(key, 0.0, -kHuge, kHuge);
      },
      [key, value, given](const SceneDraft& d, Json& j) {
        if (d.scene.runout.*given) j[key] = d.scene.runout.*value;
      });
}

Table<SceneDraft> make_runout_table() {
  return {{
      number<SceneDraft>("front_quantile", TALUS_AT(scene.runout.front_quantile), {0.5, 1.0},
                         "front = the s below which this share of the mass lies"),
      number<SceneDraft>("tail_quantile", TALUS_AT(scene.runout.tail_quantile), {0.0, 0.5},
                         "tail = the s below which this share of the mass lies"),
      present_number("gate_x", &RunoutSpec::gate_x, &RunoutSpec::has_gate, "the initial front",
                     "x of the gate; the runout is measured from it (`run` and `check` warn when it lies inside the bodies' "
                     "footprint along x)"),
      present_number("runout_plane_x", &RunoutSpec::runout_plane_x, &RunoutSpec::has_runout_plane,
                     "the end of the terrain's last transition (none outside the grid)", "x where the runout plane starts (`run` and `check` warn "
                     "when it lies upslope of the gate)"),
      custom<SceneDraft>(
          "deposit_cell", "number [m]", "`grid.cell_size`", "> 0, at most 1e7 raster cells",
          "cell of the deposit thickness raster in (s, y)", {{"type", "number"}, {"exclusiveMinimum", 0}},
          [](ObjectReader& r, SceneDraft& d) {
            const Scene& s = d.scene;
            RunoutSpec& rs = d.scene.runout;
            rs.deposit_cell = r.number_or("deposit_cell", s.grid.h, 0.0, kHuge, true);
            const double raster_cells =
                (s.grid.cells[0] * s.grid.h / rs.deposit_cell) * (s.grid.cells[1] * s.grid.h / rs.deposit_cell);
            if (raster_cells > 1e7)
              throw input_error(fmt::format("{} = {} makes a deposit raster of {:.3g} cells over the grid; at most 1e7",
                                            r.key_path("deposit_cell"), rs.deposit_cell, raster_cells));
          },
          [](const SceneDraft& d, Json& j) { j["deposit_cell"] = d.scene.runout.deposit_cell; }),
  }};
}
constexpr auto runout_table = &table_of<SceneDraft, make_runout_table>;

// "diagnostics": {"runout": {...}} (docs/flume.md "Runout diagnostics").
Table<SceneDraft> make_diagnostics_table() {
  return {{
      object<SceneDraft>(
          "runout", runout_table, "absent (off)",
          "runout diagnostics along the flume coordinate s (arc length of the terrain, x when flat): `runout.csv`, "
          "`runout.json`, `deposit.csv` (docs/flume.md §4). Measured along +x: `run` and `check` warn where the bed "
          "under the bodies rises along +x (over their footprint along x; on a flat grid, gravity[0] < 0)",
          {.begin = [](SceneDraft& d) { d.scene.runout.enabled = true; },
           .present = [](const SceneDraft& d) { return d.scene.runout.enabled; }}),
  }};
}
constexpr auto diagnostics_table = &table_of<SceneDraft, make_diagnostics_table>;

// ---- the top level -------------------------------------------------------------------------------

/// A section read with its own table; `optional`: the section may be left out.
Field<SceneDraft> section(const char* key, const Table<SceneDraft>& (*table)(), bool optional, const std::string& doc) {
  return object<SceneDraft>(key, table, optional ? "" : "required", doc, {}, {.required = !optional}, false);
}

void resolve_smoothing_bodies(SceneDraft& d) {
  Scene& s = d.scene;
  const std::vector<std::string>& names = d.smoothing_bodies;
  for (std::size_t i = 0; i < names.size(); ++i) {
    int found = -1;
    std::string known;
    for (std::size_t b = 0; b < s.bodies.size(); ++b) {
      if (s.bodies[b].name == names[i]) found = static_cast<int>(b);
      known += (known.empty() ? "" : ", ") + s.bodies[b].name;
    }
    if (found < 0)
      throw input_error(
          fmt::format("solver.smoothing.bodies[{}] = \"{}\" names no body (defined: {})", i, names[i], known));
    if (std::find(s.smoothing.bodies.begin(), s.smoothing.bodies.end(), found) != s.smoothing.bodies.end())
      throw input_error(fmt::format("solver.smoothing.bodies[{}] = \"{}\" is named twice", i, names[i]));
    s.smoothing.bodies.push_back(found);
  }
}

/// A required key that holds many entries of one table (materials by name, bodies in a list): no
/// docs row of its own; the entries' rows appear under `entry` ("<name>", "[i]").
template <class M>
Field<SceneDraft> entries(Field<SceneDraft> f, const Table<M>& table, const std::string& entry) {
  f.info.required = true;
  f.info.fallback = "required";
  f.info.row = false;
  f.info.member_rows = doc_rows(table, entry);
  return f;
}

Field<SceneDraft> materials_field() {
  const Table<MaterialSpec>& materials = material_table();
  Field<SceneDraft> f = custom<SceneDraft>(
      "materials", "object", "required", "at least one; names not empty", "the materials, by name",
      {{"type", "object"},
       {"minProperties", 1},
       {"propertyNames", {{"minLength", 1}}},
       {"additionalProperties", schema_of(materials)}},
      [](ObjectReader& r, SceneDraft& d) {
        ObjectReader mats = r.object("materials");
        const Json& mj = r.raw("materials");
        for (auto it = mj.begin(); it != mj.end(); ++it) {
          // (a body's "material": "" then named it, and messages said materials. for its keys)
          if (it.key().empty())
            throw input_error("materials has a material named \"\": give it a name (bodies refer to it by that name)");
          mats.allow(it.key());
          d.material_index[it.key()] = static_cast<int>(d.scene.materials.size());
          MaterialSpec m;
          m.name = it.key();
          ObjectReader one(it.value(), mats.key_path(it.key()));
          read_fields(one, m, material_table());
          d.scene.materials.push_back(std::move(m));
        }
        if (d.scene.materials.empty()) throw input_error("materials must define at least one material");
      },
      [](const SceneDraft& d, Json& j) {
        j["materials"] = Json::object();
        for (const MaterialSpec& m : d.scene.materials) j["materials"][m.name] = write_fields(m, material_table());
      });
  return entries(std::move(f), materials, "<name>");
}

Field<SceneDraft> bodies_field() {
  const Table<BodyDraft>& bodies = body_table();
  Json body_schema = schema_of(bodies);
  body_schema["oneOf"] = Json::array({{{"required", {"box"}}}, {{"required", {"prism"}}}});
  Field<SceneDraft> f = custom<SceneDraft>(
      "bodies", "array", "required", "1 to 65535 bodies", "the bodies filled with particles",
      {{"type", "array"}, {"minItems", 1}, {"maxItems", 65535}, {"items", body_schema}},
      [](ObjectReader& r, SceneDraft& d) {
        const Json& bj = r.raw("bodies");
        if (!bj.is_array() || bj.empty()) throw input_error("bodies must be a non-empty array of bodies");
        if (bj.size() > 65535) throw input_error("bodies: at most 65535 bodies");
        for (std::size_t i = 0; i < bj.size(); ++i) {
          BodyDraft b;
          b.scene = &d;
          ObjectReader one(bj[i], fmt::format("bodies[{}]", i));
          read_fields(one, b, body_table());
          // Smoothing selects bodies by name, and diagnostics report them by name: two of one name
          // would make both ambiguous.
          for (std::size_t k = 0; k < i; ++k)
            if (d.scene.bodies[k].name == b.body.name)
              throw input_error(fmt::format("bodies[{}].name = \"{}\" is the name of bodies[{}] as well; body names must "
                                            "differ",
                                            i, b.body.name, k));
          d.scene.bodies.push_back(std::move(b.body));
        }
        resolve_smoothing_bodies(d);
      },
      [](const SceneDraft& d, Json& j) {
        j["bodies"] = Json::array();
        for (const BodySpec& b : d.scene.bodies) j["bodies"].push_back(write_fields(BodyDraft{b, &d}, body_table()));
      });
  return entries(std::move(f), bodies, "[i]");
}

Table<SceneDraft> make_scene_table() {
  return {{
      custom<SceneDraft>(
          "comment", "any", "", "", "a note; ignored", Json::object(), [](ObjectReader& r, SceneDraft&) { r.allow("comment"); },
          [](const SceneDraft&, Json&) {}),
      custom<SceneDraft>(
          "name", "string", "`\"scene\"`", "letters, digits, `_`, `-`, `.`; not starting with `.`",
          "names the default output folder `runs/<name>`",
          {{"type", "string"}, {"default", "scene"}, {"pattern", "^[A-Za-z0-9_-][A-Za-z0-9_.-]*$"}},
          [](ObjectReader& r, SceneDraft& d) {
            // The name becomes a folder under runs/, whose output files a run replaces: a name such as
            // "..", "" or "a/b" would put them (and the clearing of an earlier run's) elsewhere.
            const std::string name = r.string_or("name", "scene");
            const bool plain = !name.empty() && name.size() <= 200 && name[0] != '.' &&
                               std::all_of(name.begin(), name.end(), [](char c) {
                                 return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
                               });
            if (!plain)
              throw input_error(fmt::format("name = {} must be a plain folder name (1-200 letters, digits, '_', '-', "
                                            "'.'; not starting with '.')",
                                            Json(name).dump()));
            d.scene.name = name;
          },
          [](const SceneDraft& d, Json& j) { j["name"] = d.scene.name; }),
      string<SceneDraft>("description", TALUS_AT(scene.description), "free text, printed by `talus check`"),
      section("grid", grid_table, false, "the grid: a box of cubic cells"),
      vec3<SceneDraft>("gravity", TALUS_AT(scene.gravity), "body force per unit mass. On a terrain grid `run` and `check` warn about a component along x or y (the "
                       "terrain tilts the bed: the slope counted twice), one up (+z), or |g| outside [1, 50] m/s²",
                       {.type = "[gx, gy, gz]"}),
      section("time", time_table, false, "the time span and the time step"),
      section("solver", solver_table, true, "the update scheme, shape functions and their options"),
      materials_field(),
      bodies_field(),
      section("boundaries", boundaries_table, true, "the walls on the six faces of the grid (see \"Boundaries\")"),
      section("output", output_table, true, "what a run writes, and how often"),
      section("guards", guards_table, true, "instability guards (docs/reliability.md)"),
      section("diagnostics", diagnostics_table, true, "diagnostics written beside the frames"),
  }};
}

}  // namespace

const Table<SceneDraft>& scene_table() {
  static const Table<SceneDraft> table = make_scene_table();
  return table;
}

const Table<DruckerPragerParameters>& drucker_prager_table() {
  static const Table<DruckerPragerParameters> table = [] {
    using P = DruckerPragerParameters;
    Table<P> t;
    t.fields = join<P>({
        {number<P>("young", TALUS_AT(young), {0.0, kHuge, true}, "Young's modulus E [Pa]", {.required = true}),
         number<P>("poisson", TALUS_AT(poisson), {0.0, 0.5, false, true}, "Poisson's ratio ν", {.required = true})},
        drucker_prager_strength_fields(),
        {check<P>([](ObjectReader& r, P& p) { with_key_path(r.path() + ".", [&] { (void)DruckerPrager(p); }); })},
    });
    return t;
  }();
  return table;
}

const Table<MuIParameters>& mu_i_table() {
  static const Table<MuIParameters> table = [] {
    using P = MuIParameters;
    Table<P> t;
    t.fields = join<P>({
        {number<P>("young", TALUS_AT(young), {0.0, kHuge, true}, "Young's modulus E [Pa]", {.required = true}),
         number<P>("poisson", TALUS_AT(poisson), {0.0, 0.5, false, true}, "Poisson's ratio ν", {.required = true})},
        mu_i_fields(),
        {check<P>([](ObjectReader& r, P& p) { with_key_path(r.path() + ".", [&] { (void)MuI(p); }); })},
    });
    return t;
  }();
  return table;
}

}  // namespace talus::scene_detail
