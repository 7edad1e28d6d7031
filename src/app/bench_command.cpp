// `talus bench`: fixed, documented 3D scenes at a chosen size; prints and writes particle-updates per
// second, seconds per phase and memory per particle. Under mpirun the scene is split over the ranks
// as `talus run` splits it (slabs along x); rank 0 prints and writes for all of them. See
// docs/performance.md, "Distributed runs (MPI)".
#include "build_info.hpp"
#include "host_info.hpp"
#include "commands.hpp"
#include "option_checks.hpp"
#include "talus/core/comm.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/core/error.hpp"
#include "talus/core/version.hpp"
#include "talus/driver/run_outputs.hpp"
#include "talus/driver/warning.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/material/drucker_prager.hpp"
#include "talus/material/mu_i.hpp"
#include "talus/solver/memory_estimate.hpp"
#include "talus/solver/solver.hpp"


#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <ctime>
#include <functional>
#include <initializer_list>
#include <limits>
#include <memory>
#include <ostream>
#include <tuple>
#include <optional>
#include <string>
#include <vector>

namespace talus::app {

namespace {

struct BenchOptions {
  std::string scene = "block";
  long long particles = 1000000;
  std::string shape = "linear";
  std::string scheme = "musl";
  std::string material = "elastic";
  std::string mls = "off";
  double mls_radius = 2.0;
  std::string mls_variant = "particle";
  double mls_reuse_strain = MlsSettings{}.reuse_strain;
  int threads = 0;
  int steps = 20;
  bool stream = false;  // also measure the STREAM triad bandwidth at the same thread count
  bool cpu_time = false;  // phases and rate on the process's CPU time (phase_timer.hpp)
  std::string json_path;
  std::string record_path;  // --record-work: the work-distribution record of extra steps
  int record_steps = 3;
  int block_cells = 0;  // solver.block_cells (0: automatic)
  std::string scatter = "colour_passes";  // solver.scatter
};

/// The STREAM triad a[i] = b[i] + s c[i] (McCalpin) over three arrays of 2^24 doubles (128 MiB
/// each, far beyond any cache), first-touched by the threads that use them; the best of 5 passes,
/// counted as 24 bytes per element as STREAM does. It gives the memory bandwidth the MPM step can
/// hope for at this thread count, measured in the same process (docs/performance.md). Under mpirun
/// every rank runs it at once (a barrier before each pass), and the ranks' rates are summed: the
/// bandwidth of the node as the ranks share it.
double stream_triad_bytes_per_second(const Comm& comm) {
  const std::size_t n = std::size_t(1) << 24;
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  }
  double best = 1e300;
  for (int pass = 0; pass < 5; ++pass) {
    comm.barrier();
    const auto start = std::chrono::steady_clock::now();
    const double scalar = 3.0 + pass;
    double* pa = a.get();
    const double* pb = b.get();
    const double* pc = c.get();
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) pa[i] = pb[i] + scalar * pc[i];
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  if (a[n / 2] != 1.0 + 7.0 * 2.0) throw io_error("stream triad: wrong result");  // keeps the loop honest
  return comm.sum_in_rank_order(24.0 * double(n) / best);
}

/// The sand the `dp` material and the column scene use: Abe, Johansson & Konagai 2005, Table 2 (E = 2 MPa, nu = 0.3,
/// phi = 40 deg, psi = 0, c = 10 Pa, no hardening, combined-hardening parameter 0.8 -> kinematic
/// fraction 0.2), density kBenchDensity. The update scene builds its model from these, the step
/// scenes read them from their scene text (material_json).
DruckerPragerParameters bench_sand() {
  DruckerPragerParameters sand;
  sand.young = 2.0e6;
  sand.poisson = 0.3;
  sand.friction_angle_deg = 40.0;
  sand.dilatancy_angle_deg = 0.0;
  sand.cohesion = 10.0;
  sand.hardening_modulus = 0.0;
  sand.kinematic_fraction = 0.2;
  return sand;
}
constexpr double kBenchDensity = 1600.0;  // [kg/m^3] the sand's and the beads'
constexpr double kBenchCell = 0.01;       // [m]

/// The scene file's keys of the bench material `material` (--material): `dp` the sand; `mu_i` the
/// glass beads of Jop et al. 2006 (the model's defaults), with the sand's elasticity and density so
/// that the time step and the waves match the `dp` bench; `elastic` a linear elastic solid.
/// (fmt's shortest form of each number reads back as the same double.)
std::string material_json(const std::string& material) {
  const DruckerPragerParameters sand = bench_sand();
  if (material == "dp")
    return fmt::format(R"("model": "drucker_prager", "density": {}, "young": {}, "poisson": {},
    "friction_angle": {}, "dilatancy_angle": {}, "cohesion": {}, "hardening_modulus": {},
    "kinematic_fraction": {})",
                       kBenchDensity, sand.young, sand.poisson, sand.friction_angle_deg, sand.dilatancy_angle_deg,
                       sand.cohesion, sand.hardening_modulus, sand.kinematic_fraction);
  if (material == "mu_i")
    return fmt::format(R"("model": "mu_i", "density": {}, "young": {}, "poisson": {})", kBenchDensity, sand.young,
                       sand.poisson);
  return R"("model": "linear_elastic", "density": 2000.0, "young": 1.0e7, "poisson": 0.3)";
}

/// The smoothing keys of --mls linear|quadratic|cubic: MLS smoothing of the strain increments (Edo
/// & Matsubara 2015, eq. 54) with the radius --mls-radius (cells, default 2) over all three axes;
/// nothing with --mls off.
std::string smoothing_json(const BenchOptions& o) {
  if (o.mls == "off") return std::string();
  return fmt::format(R"(, "smoothing": {{ "basis": "{}", "radius_factor": {}, "variant": "{}"{} }})", o.mls, o.mls_radius,
                     o.mls_variant,
                     o.mls_variant == "reused" ? fmt::format(R"(, "reuse_strain": {})", o.mls_reuse_strain) : std::string());
}

/// Where a bench scene's box body lies in its grid: the block's and the column's differ in this alone.
struct BenchLayout {
  std::string name;
  double grid_xy = 0.0;         // the square grid's side [m]
  double grid_z = 0.0;          // its height [m]
  double body_lo = 0.0;         // the body's extent along x and along y [m]
  double body_hi = 0.0;
  double body_top = 0.0;        // its height [m]
  double floor_friction = 0.0;  // the floor's friction coefficient
  std::string body_extra;       // keys added to the body (e.g. its velocity)
};

/// The scene of both benches: one box body of the bench material (2x2x2 particles per 1 cm cell)
/// on a frictional floor, open at the top, as `layout` places it, with the options' shape, scheme,
/// material, smoothing (--mls), block size (--block-cells) and scatter (--scatter).
Scene bench_scene(const BenchLayout& layout, const BenchOptions& o) {
  const std::string json = fmt::format(R"({{
    "name": "{0}",
    "grid": {{ "origin": [0, 0, 0], "size": [{1}, {1}, {2}], "cell_size": {3} }},
    "time": {{ "end": 1.0e9, "courant": 0.3 }},
    "solver": {{ "shape": "{4}", "scheme": "{5}", "block_cells": {13}, "scatter": "{14}"{6} }},
    "materials": {{ "m": {{ {7} }} }},
    "bodies": [ {{ "name": "body", "material": "m", "box": {{ "min": [{8}, {8}, 0], "max": [{9}, {9}, {10}] }},
                  "particles_per_cell": 2{11} }} ],
    "boundaries": {{ "z-": {{ "type": "friction", "friction_coefficient": {12} }}, "z+": "open" }}
  }})", layout.name, layout.grid_xy, layout.grid_z, kBenchCell, o.shape, o.scheme, smoothing_json(o),
                                       material_json(o.material), layout.body_lo, layout.body_hi, layout.body_top,
                                       layout.body_extra, layout.floor_friction, o.block_cells, o.scatter);
  return parse_scene(json, layout.name);
}

/// The block scene: a cube of about N particles sliding (0.5, 0.2, 0) m/s on a floor with mu = 0.3,
/// in a grid with room around it. Shear waves from the settling keep every particle's stress
/// changing, so no phase can take a shortcut.
Scene block_scene(const BenchOptions& o) {
  const int side = std::max(2, static_cast<int>(std::lround(std::cbrt(o.particles / 8.0))));  // cells per edge
  const double h = kBenchCell, edge = side * h;
  return bench_scene({.name = "bench_block",
                      .grid_xy = edge + 8 * h,
                      .grid_z = edge + 4 * h,
                      .body_lo = 4 * h,
                      .body_hi = 4 * h + edge,
                      .body_top = edge,
                      .floor_friction = 0.3,
                      .body_extra = R"(, "velocity": [0.5, 0.2, 0])"},
                     o);
}

/// The column scene: a square column of sand (height = 2 x width, about N particles) released at
/// t = 0 on a floor with mu = 0.5. It collapses and spreads, yielding more and more; in the bench's
/// first steps only a few particles near the floor yield (the bench prints the share; the shear
/// scene is the one with nearly all of them plastic). The grid leaves room for the runout.
Scene column_scene(const BenchOptions& o) {
  const int side = std::max(2, static_cast<int>(std::lround(std::cbrt(o.particles / 16.0))));  // cells across
  const double h = kBenchCell;
  const double width = side * h, height = 2 * side * h, room = 1.5 * width + 4 * h;
  return bench_scene({.name = "bench_column",
                      .grid_xy = width + 2 * room,
                      .grid_z = height + 4 * h,
                      .body_lo = room,
                      .body_hi = room + width,
                      .body_top = height,
                      .floor_friction = 0.5,
                      .body_extra = ""},
                     o);
}

/// The words of `values` as the scene file spells them (their to_string): the bench's options take
/// the scene's words, and name them in their help and their refusals.
template <class Enum>
std::vector<std::string> words_of(std::initializer_list<Enum> values) {
  std::vector<std::string> words;
  for (const Enum value : values) words.emplace_back(to_string(value));
  return words;
}
std::vector<std::string> shape_words() {
  return words_of({ShapeKind::Linear, ShapeKind::UGimp, ShapeKind::CpGimp, ShapeKind::BSpline2});
}
std::vector<std::string> scheme_words() {
  return words_of({SchemeKind::Musl, SchemeKind::Usl, SchemeKind::Usf, SchemeKind::Usavg});
}
std::vector<std::string> mls_words() {  // "off", then the bases
  std::vector<std::string> words = words_of({MlsBasis::Linear, MlsBasis::Quadratic, MlsBasis::Cubic});
  words.insert(words.begin(), "off");
  return words;
}
std::vector<std::string> mls_variant_words() {
  return words_of({MlsVariant::Particle, MlsVariant::Cell, MlsVariant::Reused});
}
std::vector<std::string> scatter_words() { return words_of({ScatterOrder::ColourPasses, ScatterOrder::BlockBuffers}); }

/// Refuses the value `value` of `option` unless it is one of `allowed`, naming those.
void require_one_of(const char* option, const std::string& value, const std::vector<std::string>& allowed) {
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end())
    throw input_error(fmt::format("{} {}: unknown; available: {}", option, value, fmt::join(allowed, ", ")));
}

void refuse_unavailable(const BenchOptions& o) {
  require_one_of("--shape", o.shape, shape_words());
  require_one_of("--scheme", o.scheme, scheme_words());
  require_one_of("--scene", o.scene, {"block", "column", "shear", "update"});
  if ((o.scene == "shear" || o.scene == "update") && o.material != "dp" && o.material != "mu_i")
    throw input_error(fmt::format("--scene {} needs --material dp or mu_i (the material is put at its yield stress)", o.scene));
  require_one_of("--material", o.material, {"elastic", "dp", "mu_i"});
  require_one_of("--mls", o.mls, mls_words());
  require_one_of("--mls-variant", o.mls_variant, mls_variant_words());
  // The update scene times the constitutive update alone, on the wall clock, with no solver: the
  // grid's, the smoother's and the measurements' options were ignored without a word (a scaling
  // study with --record-work then found no record).
  const BenchOptions defaults;
  // (option, its value as given, whether it was given)
  using Given = std::tuple<const char*, std::string, bool>;
  const std::vector<Given> smoother_options = {
      {"--mls-radius", fmt::format("{}", o.mls_radius), o.mls_radius != defaults.mls_radius},
      {"--mls-variant", o.mls_variant, o.mls_variant != defaults.mls_variant},
      {"--mls-reuse-strain", fmt::format("{}", o.mls_reuse_strain), o.mls_reuse_strain != defaults.mls_reuse_strain}};
  if (o.scene == "update") {
    std::vector<Given> ignored = {
        {"--shape", o.shape, o.shape != defaults.shape}, {"--scheme", o.scheme, o.scheme != defaults.scheme},
        {"--mls", o.mls, o.mls != defaults.mls}, {"--scatter", o.scatter, o.scatter != defaults.scatter},
        {"--block-cells", std::to_string(o.block_cells), o.block_cells != defaults.block_cells}};
    ignored.insert(ignored.end(), smoother_options.begin(), smoother_options.end());
    ignored.insert(ignored.end(), {{"--record-work", o.record_path, !o.record_path.empty()},
                                   {"--stream", std::string(), o.stream},
                                   {"--cpu-time", std::string(), o.cpu_time}});
    for (const auto& [option, value, given] : ignored)
      if (given)
        throw input_error(fmt::format("{}{}{}: the update scene times the constitutive update alone, with no grid, "
                                      "smoother or work record, on the wall clock; leave {} out",
                                      option, value.empty() ? "" : " ", value, option));
  }
  // The smoother's options without --mls benchmarked the step without smoothing, under a header that
  // said so but with an exit status that did not (a user who forgot --mls got the wrong method's numbers).
  if (o.mls == "off")
    for (const auto& [option, value, given] : smoother_options)
      if (given)
        throw input_error(fmt::format("{} {} needs --mls linear, quadratic or cubic (smoothing is off without it)",
                                      option, value));
  if (o.mls_variant != "reused" && o.mls_reuse_strain != defaults.mls_reuse_strain)
    throw input_error(fmt::format("--mls-reuse-strain {} needs --mls-variant reused (the {} fit does not reuse)",
                                  o.mls_reuse_strain, o.mls_variant));
}

/// The shear scene: the block scene's sand put into steady simple shear at its yield stress, so that
/// every particle takes the plastic (cone) return in every step, the flowing state of a runout.
/// Velocity v_x = rate (z - z_mid); stress -p I + tau (e_x e_z + e_z e_x) with the overburden
/// p = rho g (z_top - z) + 1 kPa and tau = k + 3 alpha p, i.e. f = alpha I1 + q - k = 0 (Abe, Johansson & Konagai 2005
/// eq. 23, q = tau in pure shear). The shear rate 1/s loads the stress by G dt per step, far more
/// than round-off, so each step's trial lies outside the cone.
/// With --material mu_i the stress is tau = mu(I) p, I from the imposed rate (Jop et al. 2006,
/// friction law and inertial number): the steady state, in which every particle takes the flowing return.
void start_in_simple_shear(Solver& solver) {
  const Scene& scene = solver.scene();
  const MaterialSpec& m = scene.materials.at(0);
  // The yield (DP) or steady-flow (mu(I)) shear stress at overburden p under the 1/s rate.
  std::function<double(double)> yield_tau;
  if (m.model == MaterialModel::MuI) {
    yield_tau = [beads = MuI(m.mu_i)](double pressure) {
      return beads.friction(beads.inertial_number(1.0, pressure)) * pressure;
    };
  } else {
    yield_tau = [model = DruckerPrager(m.drucker_prager)](double pressure) {
      return model.initial_strength() + 3.0 * model.alpha() * pressure;
    };
  }
  ParticleStore& P = solver.edit_particles();
  double z_low = std::numeric_limits<double>::infinity(), z_top = -z_low;
  for (double z : P.x[2]) {
    z_low = std::min(z_low, z);
    z_top = std::max(z_top, z);
  }
  z_low = solver.comm().min(z_low);  // a distributed run: the body's extent over every rank's slab
  z_top = -solver.comm().min(-z_top);
  const double z_mid = 0.5 * (z_low + z_top), rate = 1.0, g = std::abs(scene.gravity[2]);
  for (std::size_t p = 0; p < P.size(); ++p) {
    const double pressure = m.density * g * (z_top - P.x[2][p]) + 1.0e3;
    P.v[0][p] = rate * (P.x[2][p] - z_mid);
    P.v[1][p] = P.v[2][p] = 0.0;
    for (int c = 0; c < 3; ++c) P.stress[c][p] = -pressure;
    P.stress[YZ][p] = P.stress[XY][p] = 0.0;
    P.stress[XZ][p] = yield_tau(pressure);
  }
}

void record_work(Solver& solver, const BenchOptions& o, const nlohmann::json& bench);

/// A bench scene too large for this machine stops before it allocates (--particles 1e8 at ~300 B
/// each was killed by the kernel's out-of-memory killer), with the count that fits. `bytes`: what
/// the scene of `seeded` particles (about the count asked for) holds at its peak, in proportion to them.
void require_bench_fits(long long particles, std::size_t seeded, double bytes, const char* what) {
  const std::optional<std::size_t> available = available_memory();
  if (!available || bytes <= double(*available)) return;
  // the bench's grid grows with its particles: what fits is in proportion
  const double fits = double(seeded) * double(*available) / bytes;
  const double suggested = std::floor(0.9 * fits / 1000.0) * 1000.0;  // 10% spare: the program and the allocator
  throw input_error(fmt::format("--particles {} needs about {} ({:.0f} B a particle{}) but {} is available{}; {}",
                                particles, format_bytes(bytes), bytes / double(seeded), what,
                                format_bytes(double(*available)),
                                std::getenv("TALUS_MEMORY_LIMIT") ? " (TALUS_MEMORY_LIMIT)" : "",
                                suggested >= 1000.0 ? fmt::format("use --particles {:.0f} or fewer", suggested)
                                                    : std::string("not even --particles 1000 fits")));
}

/// What every bench JSON records beside its figures, so that one read later names where, when and
/// how it was measured: the host (name, CPU, logical CPUs and those this process may use), the date
/// and the OpenMP settings.
void add_provenance(nlohmann::json& j) {
  j["date"] = utc_text(std::time(nullptr));
  j["host"] = host_json();
  j["openmp"] = WorkRecorder::openmp_settings();
}

/// A rate measured with more threads than this process has CPUs is the oversubscription's, not the
/// machine's: said beside it (the JSON's host.cpus_allowed records it too).
void note_oversubscription(int threads) {
  if (const auto note = oversubscription(threads)) fmt::print("  note: {}, the rate is not this machine's\n", *note);
}

/// The update scene: the constitutive update alone, as BodyMaterials runs it per particle (objective
/// rotation, then the model), over N particles held in structure-of-arrays like the particle store,
/// each in simple shear at its yield stress (overburden p = 1 kPa ... 17 kPa across the particles)
/// with the increment of a 1/s shear rate over dt = 1e-4 s, so that every particle takes the plastic
/// return in every pass. No grid, no transfers: the ratio of two materials here is the ratio of
/// their updates per particle (docs/performance.md, "μ(I) against Drucker-Prager").
void run_update_bench(const BenchOptions& o) {
  const std::size_t n = static_cast<std::size_t>(o.particles);
  require_bench_fits(o.particles, n, double(n) * 7.0 * sizeof(double), "");  // the stress and the plastic strain
  set_threads(o.threads);
  const double dt = 1.0e-4, rate = 1.0;
  std::array<std::vector<double>, 6> stress;
  for (auto& c : stress) c.assign(n, 0.0);
  std::vector<double> plastic(n, 0.0);
  const DruckerPragerParameters dp = bench_sand();
  const DruckerPrager sand(dp);
  MuIParameters mi;  // the glass beads, with the sand's elasticity (material_json)
  mi.young = dp.young;
  mi.poisson = dp.poisson;
  const MuI beads(mi);
  for (std::size_t p = 0; p < n; ++p) {
    const double pressure = 1.0e3 + 1.6e4 * double(p) / double(n);
    const double tau = o.material == "dp" ? sand.initial_strength() + 3.0 * sand.alpha() * pressure
                                          : beads.friction(beads.inertial_number(rate, pressure)) * pressure;
    for (int c = 0; c < 3; ++c) stress[c][p] = -pressure;
    stress[XZ][p] = tau;
  }
  Sym6 de = Sym6::Zero();
  de[XZ] = 0.5 * rate * dt;
  const double w_xz = 0.5 * rate * dt;  // v_x = rate z: w_xz = dt (dv_x/dz - dv_z/dx) / 2, as the strain pass
  std::size_t plastic_updates = 0;
  double dissipated = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (int step = 0; step < o.steps; ++step) {
#pragma omp parallel for schedule(static) reduction(+ : plastic_updates, dissipated)
    for (std::size_t p = 0; p < n; ++p) {
      Sym6 s;
      for (int c = 0; c < 6; ++c) s[c] = stress[c][p];
      rotate_objectively(s, 0.0, w_xz, 0.0);
      if (o.material == "dp") {
        DruckerPragerState state;
        state.equivalent_plastic_strain = plastic[p];
        const DruckerPragerResult r = sand.update(s, state, de);
        plastic_updates += r.regime != DruckerPragerResult::Regime::Elastic ? 1 : 0;
        dissipated += r.plastic_work;
        plastic[p] = state.equivalent_plastic_strain;
      } else {
        const MuIResult r = beads.update(s, de, dt);
        plastic_updates += r.regime == MuIResult::Regime::Flowing ? 1 : 0;
        dissipated += r.plastic_work;
        plastic[p] += r.plastic_shear_strain;
      }
      for (int c = 0; c < 6; ++c) stress[c][p] = s[c];
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rate_updates = double(n) * o.steps / wall;
  const int threads = omp_get_max_threads();
  fmt::print("talus bench: update scene (the constitutive update alone), {} particles, {} material, {} thread{}, {} kernels, {} pass{}\n",
             n, o.material, threads, threads == 1 ? "" : "s", active_isa(), o.steps, o.steps == 1 ? "" : "es");
  fmt::print("  {:.3f} M updates/s ({:.4g} s, {:.2f} ns per particle update)\n", rate_updates / 1e6, wall,
             1e9 * wall * threads / (double(n) * o.steps));
  note_oversubscription(threads);
  fmt::print("  plastic: {:.1f}% of the updates (dissipated {:.3e} J/m^3 in all, G = {:.4g} Pa)\n",
             100.0 * double(plastic_updates) / (double(n) * o.steps), dissipated, sand.shear_modulus());
  if (!o.json_path.empty()) {
    nlohmann::json j;
    j["talus_version"] = kVersion;
    j["build"] = build_json();
    j["scene"] = "update";
    j["material"] = o.material;
    j["particles"] = n;
    j["steps"] = o.steps;
    j["threads"] = omp_get_max_threads();
    j["isa"] = active_isa();
    j["cpu"] = cpu_model();
    add_provenance(j);
    j["wall_seconds"] = wall;
    // the key every bench JSON has (the step scenes' rate; here each update is one particle's)
    j["particle_updates_per_second"] = rate_updates;
    j["plastic_share"] = double(plastic_updates) / (double(n) * o.steps);
    write_file_atomically(o.json_path, j.dump(2) + "\n");
  }
}

/// The phase `p` by name; past the last, "other": the clock outside the phases.
constexpr int kOtherPhase = static_cast<int>(Phase::Count);
const char* phase_name(int p) { return p == kOtherPhase ? "other" : kPhaseNames[p]; }

/// What each rank measured over the timed steps, gathered to every rank (Comm::allgather) so that
/// rank 0 can print the largest and the mean of each phase: the step waits for the slowest rank at
/// its exchanges, so the largest is what the run costs and max / mean shows the imbalance.
struct RankTimes {
  PhaseTimes phases;
  double wall = 0.0;               // on the phase clock (--cpu-time: this rank process's CPU time)
  std::int64_t particles = 0;      // this rank's, at the end
};

/// Per phase (and "other": the clock outside the phases, i.e. the time step and the step's
/// collective, the migration and the exchange setup at a sort) the largest and the mean over the ranks.
struct PhaseSpread {
  std::array<double, kOtherPhase + 1> max{}, mean{};
};
PhaseSpread phase_spread(const std::vector<RankTimes>& ranks) {
  PhaseSpread s;
  for (const RankTimes& r : ranks) {
    for (int p = 0; p <= kOtherPhase; ++p) {
      const double seconds = p == kOtherPhase ? std::max(0.0, r.wall - r.phases.total()) : r.phases.seconds[p];
      s.max[p] = std::max(s.max[p], seconds);
      s.mean[p] += seconds / double(ranks.size());
    }
  }
  return s;
}

/// --json and --record-work, checked before the bench runs (it can take minutes). Only rank 0 writes
/// them; the other ranks stop with it, so that none waits for rank 0 in a collective.
void refuse_unwritable_outputs(const BenchOptions& o, const Comm& world) {
  std::string refusal;
  if (world.root()) {
    try {
      if (!o.json_path.empty()) check_writable_file(o.json_path, "--json");
      if (!o.record_path.empty()) check_writable_file(o.record_path, "--record-work");
      if (!o.json_path.empty() && !o.record_path.empty() && same_file(o.json_path, o.record_path))
        throw input_error(fmt::format("--json and --record-work name the same file, {}: the one would overwrite the "
                                      "other", o.json_path));
    } catch (const Error& e) {
      refusal = e.what();
    }
  }
  if (world.any(!refusal.empty())) throw input_error(refusal);
}

/// What the timed steps of a step scene measured, over every rank (each figure a collective).
struct StepMeasures {
  std::int64_t particles = 0;       // on every rank together
  std::vector<RankTimes> rank_times;
  PhaseSpread spread;
  double wall_max = 0.0;            // the slowest rank's seconds
  double rate = 0.0;                // particle-updates per second
  DistributionStats before, after;  // the slabs around the timed steps
  double exchange_bytes_per_step = 0.0;
  double plastic_share = -1.0;      // of the particles in the last step; < 0: not measured
  std::int64_t fits_before = 0;     // MLS fits before the timed steps
  std::size_t rss = 0, rss_start = 0;
  double field_bytes = 0.0;
  std::int64_t grid_bytes = 0;
  double stream = 0.0;              // --stream: the triad's bytes per second
  std::int64_t unsmoothed = 0;      // MLS: the particles the guard left unsmoothed in the last step
  double smoothing_change = 0.0;
};

/// One untimed step, then the timed steps, with every rank's times, memory and plastic share.
/// `rss_at_start`: what the process held before the scene existed.
StepMeasures measure_steps(Solver& solver, const BenchOptions& o, std::size_t rss_at_start, const Comm& world) {
  StepMeasures m;
  solver.step();  // first step: first touch of the grid pages; not timed
  solver.phase_times() = PhaseTimes{};
  m.before = solver.distribution();  // collective: before the clock starts
  m.particles = m.before.particles;
  world.barrier();  // the ranks start the clock together
  double start = phase_clock_seconds();
  std::vector<double> plastic_before;  // eps_p before the last timed step (not timed: a copy)
  std::size_t sorts_before = 0, rss_before_copy = 0;
  m.fits_before = solver.smoothing_fits();
  double wall = 0.0;
  for (int s = 0; s < o.steps; ++s) {
    if (s + 1 == o.steps && solver.particles().has_plastic_state()) {
      wall += phase_clock_seconds() - start;
      rss_before_copy = peak_rss_bytes();  // the copy below is the bench's, not the solver's
      plastic_before.assign(solver.particles().plastic_strain.begin(), solver.particles().plastic_strain.end());
      sorts_before = solver.sort_count();
      start = phase_clock_seconds();
    }
    solver.step();
  }
  wall += phase_clock_seconds() - start;
  m.rank_times = world.allgather(RankTimes{solver.phase_times(), wall, static_cast<std::int64_t>(solver.particles().size())});
  m.spread = phase_spread(m.rank_times);
  m.wall_max = std::max_element(m.rank_times.begin(), m.rank_times.end(), [](const RankTimes& a, const RankTimes& b) {
                            return a.wall < b.wall;
                          })->wall;
  m.after = solver.distribution();
  m.exchange_bytes_per_step = double(m.after.exchange_bytes - m.before.exchange_bytes) / o.steps;
  // The share of particles whose plastic strain grew in the last step: how much of the Drucker-
  // Prager cost is the return mapping rather than the elastic trial. A sort in that step reorders
  // the particles (and moves them between ranks): then the share is not reported. The sort count
  // is the same on every rank (the sorts are collective).
  const bool comparable = solver.particles().has_plastic_state() && plastic_before.size() == solver.particles().size() &&
                          solver.sort_count() == static_cast<std::int64_t>(sorts_before);
  if (!world.any(!comparable)) {  // every rank alike, so that all take the collective below
    std::int64_t grew = 0;
    for (std::size_t p = 0; p < plastic_before.size(); ++p)
      grew += solver.particles().plastic_strain[p] > plastic_before[p] ? 1 : 0;
    m.plastic_share = double(world.sum_in_rank_order(std::vector<std::int64_t>{grew})[0]) / double(m.after.particles);
  }
  m.rate = double(m.particles) * o.steps / m.wall_max;
  // The high-water mark of the steps; with plastic state, as it was before the bench copied eps_p
  // (the steps allocate nothing, so the last step cannot raise it except by a sort's buffers).
  // Distributed: memory is summed over the ranks (each holds the program, ~25 MB, once).
  const std::vector<std::int64_t> memory = world.sum_in_rank_order(std::vector<std::int64_t>{
      static_cast<std::int64_t>(rss_before_copy > 0 ? rss_before_copy : peak_rss_bytes()),
      static_cast<std::int64_t>(rss_at_start), static_cast<std::int64_t>(solver.particles().bytes()),
      static_cast<std::int64_t>(solver.grid().active_bytes())});
  m.rss = static_cast<std::size_t>(memory[0]);
  m.rss_start = static_cast<std::size_t>(memory[1]);
  m.field_bytes = double(memory[2]);
  m.grid_bytes = memory[3];
  // after the memory high-water mark is read: the triad's 384 MiB must not count as the solver's
  m.stream = o.stream ? stream_triad_bytes_per_second(world) : 0.0;
  if (solver.smoother()) {
    m.unsmoothed = world.sum_in_rank_order(std::vector<std::int64_t>{static_cast<std::int64_t>(solver.last_smoothing().unsmoothed)})[0];
    m.smoothing_change = -world.min(-solver.last_smoothing_change());  // the largest rank's
  }
  return m;
}

/// The step scene's results as the bench JSON (--json) and the work record's "bench" hold them.
nlohmann::json bench_json(const BenchOptions& o, const Solver& solver, const StepMeasures& m, const Comm& world) {
  const std::int64_t n = m.particles;
  const int threads = omp_get_max_threads();
  nlohmann::json j;
  j["talus_version"] = kVersion;
  j["build"] = build_json();
  j["scene"] = o.scene;
  j["shape"] = o.shape;
  j["material"] = o.material;
  j["mls"] = o.mls;
  if (o.mls != "off") {
    j["mls_radius_factor"] = o.mls_radius;
    j["mls_variant"] = o.mls_variant;
  }
  j["scheme"] = to_string(solver.scene().scheme);
  j["particles"] = n;
  j["block_cells"] = solver.cell_sort().block_cells();
  j["scatter"] = to_string(solver.scene().scatter);
  j["steps"] = o.steps;
  j["ranks"] = world.size();
  j["threads"] = threads;  // per rank
  j["isa"] = active_isa();
  j["clock"] = o.cpu_time ? "process cpu" : "wall";
  j["omp_wait_policy"] = WorkRecorder::openmp_setting("OMP_WAIT_POLICY");
  j["cpu"] = cpu_model();
  add_provenance(j);
  // the slowest rank's seconds, named for the clock that measured them
  j[o.cpu_time ? "cpu_seconds" : "wall_seconds"] = m.wall_max;
  j["particle_updates_per_second"] = m.rate;
  nlohmann::json phases, phases_max, phases_mean;
  for (int p = 0; p <= kOtherPhase; ++p) {
    phases[phase_name(p)] = m.spread.max[p];  // one rank: its phases ("other" too, as printed)
    phases_max[phase_name(p)] = m.spread.max[p];
    phases_mean[phase_name(p)] = m.spread.mean[p];
  }
  j["phases"] = phases;
  j["phases_max"] = phases_max;    // over the ranks; "other": outside the phases
  j["phases_mean"] = phases_mean;
  {  // each rank's own, to see which one waits (one entry on one rank: the same keys whatever the count)
    nlohmann::json per_rank = nlohmann::json::array();
    for (const RankTimes& r : m.rank_times) {
      nlohmann::json e;
      for (int p = 0; p < kOtherPhase; ++p) e[kPhaseNames[p]] = r.phases.seconds[p];
      e["other"] = std::max(0.0, r.wall - r.phases.total());
      e["wall"] = r.wall;
      e["particles"] = r.particles;
      per_rank.push_back(e);
    }
    j["rank_phases"] = per_rank;
  }
  j["exchange_bytes_per_step"] = m.exchange_bytes_per_step;  // node sums sent by all ranks together
  j["imbalance"] = m.after.imbalance;                         // largest rank's particles / mean, at the end
  j["max_imbalance"] = m.after.max_imbalance;
  j["shared_tiles"] = m.after.shared_tiles;
  j["migrated"] = m.after.migrated - m.before.migrated;         // in the timed steps
  j["rebalances"] = m.after.rebalances - m.before.rebalances;
  j["sorts"] = solver.sort_count();
  if (m.plastic_share >= 0.0) j["plastic_share_last_step"] = m.plastic_share;
  if (const MlsStrainSmoother* mls = solver.smoother()) {
    j["mls_radius"] = mls->radius();
    j["mls_terms"] = mls->term_count();
    j["mls_unsmoothed_last_step"] = m.unsmoothed;
    j["mls_strain_change_last_step"] = m.smoothing_change;
    j["mls_fits"] = solver.smoothing_fits() - m.fits_before;  // in the timed steps
    j["mls_weight_bytes_per_particle"] = double(solver.mls_weight_bytes()) / n;
  }
  j["bytes_per_particle"] = double(m.rss) / n;
  j["particle_field_bytes_per_particle"] = m.field_bytes / n;
  j["grid_active_bytes"] = m.grid_bytes;
  j["peak_rss_bytes"] = m.rss;
  j["rss_at_start_bytes"] = m.rss_start;
  j["bytes_per_particle_above_start"] = double(m.rss - std::min(m.rss, m.rss_start)) / n;
  if (o.stream) j["stream_triad_bytes_per_second"] = m.stream;
  return j;
}

/// The step scene's results on stdout.
void print_bench(const BenchOptions& o, const Solver& solver, const StepMeasures& m, const Comm& world) {
  const std::int64_t n = m.particles;
  const int threads = omp_get_max_threads();
  const std::string workers =
      world.distributed() ? fmt::format("{} ranks x {} thread{}", world.size(), threads, threads == 1 ? "" : "s")
                          : fmt::format("{} thread{}", threads, threads == 1 ? "" : "s");
  fmt::print("talus bench: {} scene, {} particles, {} shape, {} scheme, {} material, MLS {}, {}, {} kernels, {} step{}\n",
             o.scene, n, o.shape, o.scheme, o.material,
             o.mls == "off" ? o.mls
                            : fmt::format("{} ({} fit, radius {} cells)", o.mls, o.mls_variant, o.mls_radius),
             workers, active_isa(), o.steps, o.steps == 1 ? "" : "s");
  // (the phase times below are totals over the timed steps too; a reader took them for one step's)
  fmt::print("  {:.3f} M particle-updates/s ({:.4g} s{} over the {} timed step{}; the phases below are totals over "
             "them)\n", m.rate / 1e6, m.wall_max, o.cpu_time ? " of CPU time" : "", o.steps, o.steps == 1 ? "" : "s");
  note_oversubscription(threads);
  if (o.cpu_time && threads > 1)  // (a 2-thread run printed a third of its wall-clock rate, without a word)
    fmt::print("  note: --cpu-time sums the CPU time of the {} threads: the rate is per second of one core, not of the "
               "wall clock\n", threads);
  if (threads > 1 && WorkRecorder::passive_wait_policy())
    fmt::print("  note: OMP_WAIT_POLICY=PASSIVE: the threads sleep between parallel regions and each region wakes them "
               "(11-15 us a region at 2 threads, 38-218 us at 16 on a 16-core VM): unset it to time talus rather than the wake-ups\n");
  if (!world.distributed()) {
    const double total = solver.phase_times().total();
    for (int p = 0; p < kOtherPhase; ++p)
      fmt::print("  {:<7} {:8.4f} s  {:5.1f}%\n", kPhaseNames[p], solver.phase_times().seconds[p],
                 100.0 * solver.phase_times().seconds[p] / std::max(total, 1e-300));
  } else {
    // Shares of the slowest rank's wall; max / mean > 1 is time some rank spent that another did
    // not (its extra work, or its wait for a neighbour at an exchange, inside p2g and remap).
    fmt::print("  {:<7} {:>9} {:>9} {:>6} {:>9}\n", "phase", "max s", "mean s", "max %", "max/mean");
    for (int p = 0; p <= kOtherPhase; ++p)
      fmt::print("  {:<7} {:9.4f} {:9.4f} {:5.1f}% {:9.2f}\n", phase_name(p), m.spread.max[p], m.spread.mean[p],
                 100.0 * m.spread.max[p] / std::max(m.wall_max, 1e-300), m.spread.max[p] / std::max(m.spread.mean[p], 1e-300));
    fmt::print("  (other: outside the phases: the time step and the step's collective, migration and exchange setup at a sort)\n");
    fmt::print("  slabs: imbalance {:.3f} (largest rank's particles / mean), {:.3f} at most; {} rebalances and {} particles "
               "migrated in the timed steps; {} shared tiles; {:.1f} kB of node sums exchanged a step (all ranks)\n",
               m.after.imbalance, m.after.max_imbalance, m.after.rebalances - m.before.rebalances, m.after.migrated - m.before.migrated,
               m.after.shared_tiles, m.exchange_bytes_per_step / 1e3);
  }
  if (m.plastic_share >= 0.0)
    fmt::print("  plastic in the last step: {:.1f}% of the particles\n", 100.0 * m.plastic_share);
  else if (solver.particles().has_plastic_state())  // (the line used to vanish without a word)
    fmt::print("  plastic in the last step: not measured (the particles were sorted in that step; try another --steps)\n");
  if (o.mls_variant == "reused" && solver.smoother())
    fmt::print("  MLS: {} of the {} timed steps fitted, the rest reused the weights ({:.0f} B/particle)\n",
               solver.smoothing_fits() - m.fits_before, o.steps, double(solver.mls_weight_bytes()) / n);
  if (o.stream)
    fmt::print("  STREAM triad: {:.2f} GB/s at {}{}\n", m.stream / 1e9, world.distributed() ? "all ranks, " : "",
               workers);
  fmt::print("  memory: {:.0f} B/particle peak RSS, {:.0f} B/particle above the {:.1f} MB the process held before the scene "
             "({:.0f} B/particle in particle fields), grid {:.1f} MB active{}\n",
             double(m.rss) / n, double(m.rss - std::min(m.rss, m.rss_start)) / n, m.rss_start / 1e6, m.field_bytes / n,
             double(m.grid_bytes) / 1e6,
             world.distributed() ? " (all ranks)" : "");
}

void run_bench(const BenchOptions& o) {
  refuse_unavailable(o);
  const Comm world = Comm::world();
  refuse_unwritable_outputs(o, world);
  if (world.distributed() && o.scene == "update")
    throw input_error("--scene update: one rank only (it has no grid to split); run it without mpirun");
  if (world.distributed() && o.mls != "off")
    throw input_error(fmt::format("--mls {}: MLS smoothing is not available in a distributed run yet; run it without "
                                  "mpirun", o.mls));
  if (world.distributed() && !o.record_path.empty())
    throw input_error("--record-work: one rank only (the record is of one process's threads); run it without mpirun");
  if (o.scene == "update") {
    run_update_bench(o);
    return;
  }
  // (under mpirun: the default shared among a host's ranks; threads beyond the CPUs are said once, as by
  // run and check; each rate line below notes it too)
  if (const auto oversubscribed = oversubscription_warning(world, o.threads, set_rank_threads(o.threads, world)))
    warn("{}", *oversubscribed);
  phase_clock() = o.cpu_time ? PhaseClock::ProcessCpu : PhaseClock::Wall;
  // What the process holds before the scene exists (the program and its libraries, ~25 MB): the
  // per-particle figure without it is what a larger run costs per particle.
  const std::size_t rss_at_start = status_bytes("VmRSS:");
  Scene scene = o.scene == "column" ? column_scene(o) : block_scene(o);
  const MemoryEstimate estimate = estimate_memory(scene, MemoryScope::Solver);
  require_bench_fits(o.particles, estimate.particles, double(estimate.total()), " with the grid");
  Solver solver(std::move(scene), world);
  if (o.scene == "shear") start_in_simple_shear(solver);
  const StepMeasures measures = measure_steps(solver, o, rss_at_start, world);
  if (!world.root()) return;
  const nlohmann::json j = bench_json(o, solver, measures, world);
  print_bench(o, solver, measures, world);
  if (!o.json_path.empty()) write_file_atomically(o.json_path, j.dump(2) + "\n");
  if (!o.record_path.empty()) record_work(solver, o, j);
}

/// --record-work: `record_steps` more steps after the timed ones, recorded region by region and
/// block by block (solver/work_recorder.hpp), and the fork/join cost of an empty parallel loop at
/// 1..max(threads, cores) threads; written as JSON for tools/scaling_model.py. The timed figures
/// above come from the unrecorded steps.
void record_work(Solver& solver, const BenchOptions& o, const nlohmann::json& bench) {
  WorkRecorder recorder(o.record_steps);
  solver.record_work(&recorder);
  for (int s = 0; s < o.record_steps; ++s) solver.step();
  solver.record_work(nullptr);
  nlohmann::json meta = WorkRecorder::threading_meta();
  meta["source"] = "talus bench";
  meta["bench"] = bench;
  meta["threads"] = omp_get_max_threads();
  meta["cpu"] = cpu_model();
  meta["block_cells"] = solver.cell_sort().block_cells();
  meta["scatter"] = to_string(solver.scene().scatter);
  write_file_atomically(o.record_path, [&](std::ostream& out) { recorder.write_json(out, meta); });
  fmt::print("  work record: {} steps, {}\n", recorder.steps().size(), o.record_path);
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  auto* cmd = app.add_subcommand(
      "bench", "Measure speed: particle-updates per second, time per phase, memory per particle (under mpirun: of all ranks, with the bytes they exchange)");
  cmd->add_option("--scene", o->scene, "block (a cube sliding on a frictional floor) | column (a sand column collapsing, 2:1) | shear (the block's sand in simple shear at yield: every particle plastic every step; --material dp or mu_i) | update (the constitutive update alone, every particle plastic; --material dp or mu_i)")->capture_default_str();
  check_range(cmd->add_option("--particles", o->particles, "Approximate particle count"), 1000LL, 100000000LL)
      ->capture_default_str();
  cmd->add_option("--shape", o->shape, fmt::format("{}", fmt::join(shape_words(), " | ")))
      ->capture_default_str();
  cmd->add_option("--scheme", o->scheme, fmt::format("{}", fmt::join(scheme_words(), " | ")))
      ->capture_default_str();
  cmd->add_option("--material", o->material, "elastic | dp (Drucker-Prager sand, Abe, Johansson & Konagai 2005, Table 2) | mu_i (glass beads, Jop et al. 2006); --scene shear and update need dp or mu_i")->capture_default_str();
  cmd->add_option("--mls", o->mls, fmt::format("{}", fmt::join(mls_words(), " | ")))->capture_default_str();
  check_range(cmd->add_option("--mls-radius", o->mls_radius, "MLS radius in cells (solver.smoothing.radius_factor)"),
              0.5, 8.0)
      ->capture_default_str();
  cmd->add_option("--mls-variant", o->mls_variant,
                  "particle (one fit per particle, the reference) | cell (one fit per cell) | reused (the particle fit's "
                  "weights reused: solver.smoothing.variant)")
      ->capture_default_str();
  check_range(cmd->add_option("--mls-reuse-strain", o->mls_reuse_strain,
                              "with --mls-variant reused: the strain after which the fits are redone "
                              "(solver.smoothing.reuse_strain; 0: every step that strains)"),
              0.0, 1.0)
      ->capture_default_str();
  check_range(cmd->add_option("--threads", o->threads, "OpenMP threads (default: OMP_NUM_THREADS, else the CPUs this process "
                                                                  "may use; under mpirun shared among the ranks on the host "
                                                                  "that may use them)"), 1, 4096);
  check_range(cmd->add_option("--steps", o->steps, "Timed steps (after one untimed step)"), 1, 1000000)
      ->capture_default_str();
  refuse_empty(cmd->add_option("--json", o->json_path, "Also write the results as JSON to this file"),
               "give a file, or leave --json out");
  CLI::Option* record_work = refuse_empty(cmd->add_option("--record-work", o->record_path,
                               "Also record the work of every block and parallel region for --record-steps more steps, "
                               "as JSON (tools/scaling_model.py)"),
               "give a file, or leave --record-work out");
  check_range(cmd->add_option("--block-cells", o->block_cells,
                              "solver.block_cells: colour-block edge in cells (0: automatic, 4 for linear, 8 for the "
                              "other shapes)"),
              0, 64, "0, or 3..64 (linear), 5..64 (other shapes)")
      ->capture_default_str();
  cmd->add_option("--scatter", o->scatter,
                  "solver.scatter: colour_passes (8 passes over the colour blocks) or block_buffers (one pass into "
                  "per-block node boxes, then their sum)")
      ->check(CLI::IsMember(scatter_words()))
      ->capture_default_str();
  check_range(cmd->add_option("--record-steps", o->record_steps, "Steps recorded by --record-work"), 1, 1000)
      ->capture_default_str()
      ->needs(record_work);  // (given alone it was ignored without a word)
  cmd->add_flag("--cpu-time", o->cpu_time,
                "Time with the process's CPU time instead of the wall clock (phases and the rate): on a shared "
                "machine a 1-thread bench is then not charged for waiting for a core");
  cmd->add_flag("--stream", o->stream, "Also measure the STREAM triad memory bandwidth at the same thread count");
  auto isa = std::make_shared<std::string>();
  add_isa_option(cmd, isa);
  cmd->callback([o, isa]() {
    select_isa_option(*isa);
    run_bench(*o);
  });
}

}  // namespace talus::app
