#pragma once
// The validated description of a run: plain structs, filled in and checked by scene_json.cpp.
// The scene layer aggregates: the grid's, the bodies', the walls' and the smoother's own specs live
// in their layers (GridGeometry, BodySpec, WallSpec, MlsSettings); what only a run needs is here.
// Nothing below the solver reads JSON; everything it needs is here, with defaults resolved.
#include "talus/boundary/wall_spec.hpp"
#include "talus/core/types.hpp"
#include "talus/grid/grid.hpp"
#include "talus/material/drucker_prager.hpp"
#include "talus/material/elastic_moduli.hpp"
#include "talus/material/mu_i.hpp"
#include "talus/particles/body_spec.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/smoothing/mls_settings.hpp"

#include <array>
#include <string>
#include <vector>

namespace talus {

/// Shape functions (docs/theory.md): linear MPM, uGIMP, cpGIMP (Edo & Matsubara 2015, eq. 30-31, 57-59),
/// quadratic B-spline.
enum class ShapeKind { Linear, UGimp, CpGimp, BSpline2 };
/// Update schemes (Abe, Johansson & Konagai 2005, sec. 4(1)): MUSL, USL, USF (Bardenhagen 2002), USAVG (Nairn 2003).
enum class SchemeKind { Musl, Usl, Usf, Usavg };
/// How P2G and the MUSL remap sum the particles into the nodes without races (transfer/block_buffers.hpp):
/// 8 colour passes over the blocks (the default), or one pass into per-block node boxes and a sum of
/// the boxes (fewer, larger parallel loops for small scenes on many threads; round-off differs).
enum class ScatterOrder { ColourPasses, BlockBuffers };

enum class MaterialModel { LinearElastic, DruckerPrager, MuI };

/// What a runout scene does with Drucker-Prager particles beyond the constitutive law itself
/// (Abe, Johansson & Konagai 2005, sec. 7; docs/drucker-prager.md "In the MPM solver"). μ(I) bodies use only the
/// separation rule (docs/mu-i.md).
struct GranularOptions {
  /// A particle counts as flowing once its equivalent plastic strain exceeds this; from then on
  /// it uses `flowing_dilatancy_angle` (Abe, Johansson & Konagai 2005: "dilatancy is set to 0 once flow starts").
  double flowing_plastic_strain = 0.05;
  double flowing_dilatancy_angle_deg = 0.0;
  /// A particle whose volume exceeds this multiple of its initial volume has lost contact with
  /// its neighbours: its stress is set to zero and its plastic state reset (the stored elastic
  /// energy it held is counted as dissipated). 0 disables the rule.
  double separation_volume_ratio = 1.5;
};

struct MaterialSpec {
  std::string name;
  MaterialModel model = MaterialModel::LinearElastic;
  double density = 0.0;  // initial density [kg/m^3]
  ElasticModuli elastic;  // E and nu; for Drucker-Prager and mu(I): the elastic part (the same E, nu)
  DruckerPragerParameters drucker_prager;  // MaterialModel::DruckerPrager only (E, nu copied in)
  MuIParameters mu_i;                      // MaterialModel::MuI only (E, nu copied in)
  GranularOptions granular;                // DruckerPrager (all of it) and MuI (separation only)
};

struct OutputSpec {
  double frame_interval = 0.0;         // [s] between particle frames; 0 = first and last only
  double history_interval = 0.0;       // [s] between energy-history rows; 0 = every step
  bool compress = true;                // LZ4 inside the .vtu files
  double checkpoint_interval = 0.0;    // [s] between checkpoints (checkpoint.h5); 0 = none (still on signals)
  bool energy_gap_terms = false;       // energy.csv also gets the EnergyGapTerms columns (energy_budget.hpp)
};

/// Instability guards (docs/reliability.md): a run that trips one stops with a one-line diagnosis,
/// writes its last good state as a frame and a checkpoint, and exits with code 3.
struct GuardSpec {
  double max_step_displacement = 1.0;  // [cells] a particle may move in one step (more: CFL breach)
  double energy_growth_factor = 1.0;   // stop when the total energy grew by more than this times the energy available
  double energy_warning_factor = 0.1;  // warn once when it grew by more than this times the energy available; 0 = off
  double min_volume_ratio = 0.01;      // stop when a particle's volume falls below this times its seeded volume; 0 = off
  int snapshot_interval = 10;          // [steps] between in-memory copies of the last good state; 0 = none
};

/// MLS smoothing of the strain increments (Edo & Matsubara 2015, eq. 38-46, 54; docs/theory.md).
struct SmoothingSpec {
  bool enabled = false;
  MlsSettings mls;
  std::vector<int> bodies;  // indices into Scene::bodies of the smoothed bodies; empty = every body
};

/// Runout diagnostics (diagnostics/runout.hpp, docs/flume.md): along the flume's arc-length
/// coordinate s (s = x on a flat grid). Off unless the scene has a "diagnostics.runout" object.
struct RunoutSpec {
  bool enabled = false;
  double front_quantile = 0.995;   // front: s below which this share of the mass lies
  double tail_quantile = 0.005;    // tail: s below which this share of the mass lies
  bool has_gate = false;           // gate_x given; otherwise the initial front is the reference
  double gate_x = 0.0;             // [m] x of the gate (the runout is measured from it)
  bool has_runout_plane = false;   // runout_plane_x given (or derived from the terrain)
  double runout_plane_x = 0.0;     // [m] x where the runout plane starts
  double deposit_cell = 0.0;       // [m] raster cell (s and y) of deposit.csv (the JSON default: the grid's h)
};

struct Scene {
  std::string name;
  std::string description;
  GridGeometry grid;
  Vec3 gravity{0.0, 0.0, -9.81};
  double end_time = 1.0;
  double courant = 0.3;                // Edo & Matsubara 2015, eq. 60: c dt / h
  int max_steps = 0;                   // 0 = no limit
  SchemeKind scheme = SchemeKind::Musl;
  ShapeKind shape = ShapeKind::Linear;
  int sort_interval = 20;              // re-sort at least this often (also when a particle drifts)
  /// Edge of the colour blocks in cells (particles/cell_sort.hpp); 0 = automatic: the smallest
  /// multiple of 4 that leaves one cell of slack (4 for linear, 8 for the wider supports). Smaller
  /// blocks (down to 3 for linear, 5 for the others) give the colour passes more blocks to share
  /// among threads; the sums then run in another (still thread-independent) order.
  int block_cells = 0;
  /// The scatter's order (ScatterOrder): colour passes, or per-block boxes (not with periodic axes).
  ScatterOrder scatter = ScatterOrder::ColourPasses;
  /// Gravity (the body force) grows linearly from 0 to its full value over this time [s]; 0 = applied
  /// at once. A quasi-static load (the Bardenhagen-Kober column, Edo & Matsubara 2015, sec. 4(1)) needs it.
  double gravity_ramp_time = 0.0;
  /// The PIC share beta of the G2P velocity update, v_p = (1 - beta) FLIP + beta PIC (0 = pure FLIP,
  /// Edo & Matsubara 2015, eq. 50). A small share (the flume uses 0.01) damps the grid-scale velocity noise that
  /// otherwise keeps a granular deposit jittering; the energy it removes is the budget's `damping`.
  double pic_fraction = 0.0;
  SmoothingSpec smoothing;
  std::vector<MaterialSpec> materials;
  std::vector<BodySpec> bodies;
  // walls[axis][side]: side 0 = lower face (x-, y-, z-), side 1 = upper face.
  std::array<std::array<WallSpec, 2>, 3> walls{};
  OutputSpec output;
  GuardSpec guards;
  RunoutSpec runout;

  /// The first step's Courant time step, courant h / max over bodies of (c + |v0|), c = sqrt(M / rho):
  /// what Solver::stable_time_step gives for the freshly seeded particles, known before seeding.
  double initial_time_step() const;
  /// A body's elastic wave speed c = sqrt(M / rho) at its seeded state [m/s]; initial_time_step adds |v0|.
  double wave_speed(const BodySpec& body) const;
};

/// Settings that are valid but were measured to misbehave (each line says what was measured and
/// where it is documented); `talus run` and `talus check` print each as "talus: warning: ...".
std::vector<std::string> scene_warnings(const Scene& scene);

/// Largest MLS radius (cells) that stayed stable on the benchmarks (docs/verification.md, "MLS
/// radius"): radii of 3 cells and more went unstable on the column and the sliding block.
constexpr double kMlsStableRadiusFactor = 2.5;

const char* to_string(SchemeKind scheme);
const char* to_string(ScatterOrder order);
const char* to_string(ShapeKind shape);
const char* to_string(MaterialModel model);
const char* to_string(ConeFit cone);

/// How far a shape function's support reaches from a particle's cell, in nodes below and above.
struct ShapeReach {
  int low, high;
};
ShapeReach shape_reach(ShapeKind shape);
/// The colour blocks' edge in cells for the scene's shape and solver.block_cells (CellSort::block_edge).
int colour_block_edge(const Scene& scene);

/// Seed every body of the scene (particles/seeding.hpp with the scene's grid and densities).
/// Throws input_error for a body that holds no particle.
ParticleStore seed_particles(const Scene& scene, const SeedFilter& keep = {});
/// The seed points per padded cell along x (particles_per_x_cell).
std::vector<std::int64_t> particles_per_x_cell(const Scene& scene);
/// The number of particles seed_particles(scene) makes, without making them (same input errors).
std::size_t count_particles(const Scene& scene);

}  // namespace talus
