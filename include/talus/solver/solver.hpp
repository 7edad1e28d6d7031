#pragma once
// Solver: owns the particles, the grid and the time, and advances the scene one step at a time.
// step_with() is the one place where the order of the phases is written down (solver.cpp).
#include "talus/boundary/ghost_map.hpp"
#include "talus/boundary/walls.hpp"
#include "talus/core/comm.hpp"
#include "talus/grid/grid.hpp"
#include "talus/grid/tile_exchange.hpp"
#include "talus/grid/tile_stages.hpp"
#include "talus/solver/body_materials.hpp"
#include "talus/solver/energy_budget.hpp"
#include "talus/solver/grid_update.hpp"
#include "talus/solver/outflow_faces.hpp"
#include "talus/transfer/transfers.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_scratch.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/particles/slab_decomposition.hpp"
#include "talus/scene/scene.hpp"
#include "talus/smoothing/mls_stored_weights.hpp"
#include "talus/smoothing/mls_strain_smoother.hpp"
#include "talus/solver/phase_timer.hpp"
#include "talus/solver/work_recorder.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace talus {

/// Everything besides the particle arrays that the next step depends on: what a checkpoint saves
/// with the particles so that a restored solver continues bit for bit (docs/reliability.md).
/// A new scalar: one line in Solver::for_each_counter (state() and restore() copy through it) and
/// its attribute in io/checkpoint.cpp (written, read, and in for_each_rank_scalar or
/// for_each_rank_integer when each rank keeps its own).
struct SolverState {
  double time = 0.0;
  std::int64_t step = 0;
  double last_dt = 0.0;
  EnergyBudget work;                    // the accumulated terms (kinetic, strain, gravity stay 0)
  EnergyGapTerms gap;                   // output.energy_gap_terms: accumulated (zero when off)
  double outflow_mass = 0.0;            // [kg] of the particles removed at open faces
  OutflowFaces outflow_faces;           // the mass and count of outflow_mass, outflow_particles by face
  std::int64_t outflow_particles = 0;
  int steps_since_sort = 0;
  std::int64_t sorts = 0;
  bool needs_sort = false;
  /// [J] sum of m g.(x_wrapped - x) over the particles' periodic wraps (Solver::wrap_periodic).
  double periodic_gravity_shift = 0.0;
  /// [m] a bound on how far any particle has moved since the last sort (the MLS search's drift).
  double sort_drift = 0.0;
  /// Per particle (in the store's order): the padded grid cell it was sorted into at the last sort.
  /// restore() rebuilds the cell sort from these, so the blocks and the summation order match.
  std::array<std::vector<std::int32_t>, 3> sort_cell;
  /// MLS `reused` variant: the stored weights (null: none, the next pass fits) and the strain
  /// summed since they were fitted. From Solver::state() a view of the solver's own weights, valid
  /// until its next step (a checkpoint writes them at once; the run loop's snapshot drops them, so a
  /// restore from it fits anew); from a checkpoint, weights of their own.
  std::shared_ptr<const MlsStoredWeights> mls_weights;
  double mls_strain_since_fit = 0.0;
};

/// What a distributed run exchanged and how well its slabs are balanced (Solver::distribution).
struct DistributionStats {
  int ranks = 1;
  std::int64_t particles = 0;             // on every rank together
  double imbalance = 1.0;                 // largest rank's particles over the mean, now
  double max_imbalance = 1.0;             // the largest seen at a sort
  std::int64_t rebalances = 0;            // times the slab bounds moved
  std::int64_t migrated = 0;              // particles sent to another rank, all ranks, all sorts
  std::int64_t exchange_bytes = 0;        // node sums sent by every rank, all steps
  std::int64_t shared_tiles = 0;          // tiles held by two ranks now (each pair once)
};

class Solver {
 public:
  /// A solver over `comm`'s ranks: each holds the particles of its slab (docs/architecture.md,
  /// "Distributed runs"). The default, one rank, is a serial run.
  explicit Solver(Scene scene, Comm comm = Comm());
  /// Refuses (an input Error, as the constructor would) a scene that cannot run on `ranks` ranks:
  /// MLS smoothing, a periodic x axis, fewer colour-block columns along x than ranks. For `talus check`.
  static void check_ranks(const Scene& scene, int ranks);

  /// Advance one step with the stable time step, clipped so that the run ends at end_time.
  /// Throws an instability Error (step, time, particle, quantity) if the state goes bad.
  void step();
  /// The end time or max_steps is reached, or every particle has left through the open faces.
  bool finished() const;
  /// Every particle has left through the open faces (the run ends early, finished()).
  bool emptied() const { return emptied_; }
  /// Whether time.max_steps ended the run before time.end (a run that stopped there is complete as
  /// asked, but short of its end time: the run's last lines and run.json say so).
  bool stopped_at_max_steps() const;
  /// Steps between the scans of every particle field (stability_guards.hpp); a non-finite
  /// velocity or displacement is caught in the step it appears.
  static constexpr int kFieldCheckInterval = 8;
  /// Scan every particle field now (finite values, positive volumes); throws an instability Error.
  void check_particles() const;

  /// dt = courant * h / max_p (c_p + |v_p|) (Edo & Matsubara 2015, eq. 60), c_p the P-wave speed at the
  /// particle's current density. A scan of every particle; step() takes the maximum from the last
  /// stress pass instead when nothing has changed the particles since (the same value).
  double stable_time_step() const;

  double time() const { return time_; }
  std::int64_t step_count() const { return step_; }
  double last_dt() const { return last_dt_; }
  EnergyBudget energies() const;
  /// What the budget's gap is made of (output.energy_gap_terms; zero when off). Collective in a
  /// distributed run: each rank's terms added in rank order.
  EnergyGapTerms energy_gap_terms() const;

  const Scene& scene() const { return scene_; }
  const Comm& comm() const { return comm_; }
  const SlabDecomposition& decomposition() const { return decomposition_; }
  /// Collective in a distributed run: counts summed over the ranks.
  DistributionStats distribution() const;
  /// The rank owning a particle at x (its cell's slab); 0 in a serial run.
  int owner_of(double x) const { return decomposition_.owner_of_cell(scene_.grid.cell_of(0, x)); }
  const ParticleStore& particles() const { return particles_; }
  /// Access to change the particles (a bench's set-up, a test): the next step then scans them for
  /// its time step (the maximum kept from the last stress pass is dropped).
  ParticleStore& edit_particles() {
    wave_rate_from_stress_pass_.reset();
    return particles_;
  }
  const Grid& grid() const { return grid_; }
  const CellSort& cell_sort() const { return sort_; }
  PhaseTimes& phase_times() { return times_; }
  const PhaseTimes& phase_times() const { return times_; }
  std::int64_t sort_count() const { return sorts_; }
  /// Particles that crossed an open face of the domain are removed at the end of their step (an
  /// outflow boundary: sand falling off the open side of a flume). Their count and mass so far,
  /// over every rank (collective in a distributed run).
  std::int64_t outflow_particles() const;
  double outflow_mass() const;
  /// Mass and count that left through each face (collective in a distributed run: each rank's
  /// summed in rank order).
  OutflowFaces outflow_faces() const;
  /// The part of outflow_mass() that left through the x+ face: ahead of the flow's front, which the
  /// runout diagnostics then cannot see (collective in a distributed run).
  double outflow_mass_x_plus() const;
  /// The gravitational term (-m g.x) the particles that left carried out, all ranks: with energies()'s
  /// `gravity` it is the potential of every particle seeded, so the energy released does not depend on
  /// where the origin lies (EnergyGuard::check).
  double outflow_gravity() const;

  /// MLS smoothing (Edo & Matsubara 2015, eq. 54): the smoother, or null when the scene does not enable it;
  /// the counts of the last smoothing pass and the particle-passes left unsmoothed by its guard.
  const MlsStrainSmoother* smoother() const { return smoother_ ? &*smoother_ : nullptr; }
  MlsCounts last_smoothing() const { return last_smoothing_; }
  std::int64_t unsmoothed_total() const { return unsmoothed_total_; }
  /// The particle-passes the guard judged (the smoothed bodies' particles, summed over the passes):
  /// unsmoothed_total() is the part of them it left as they were.
  std::int64_t guarded_total() const { return guarded_total_; }
  /// How much the fit changed the strain increments in a pass: the RMS of (smoothed - raw) over
  /// every component and particle, divided by the RMS of the raw increments (0: unchanged). Of the
  /// last pass, and its mean and maximum over the passes of this solver. Measured means: 0.02-0.28
  /// on the benchmarks at 2 cells, 0.6-0.8 where a 4-cell fit breeds hourglass modes (the fit then
  /// removes nearly all of the raw increment; docs/reliability.md, "What no guard catches").
  double last_smoothing_change() const { return last_smoothing_change_; }
  double mean_smoothing_change() const { return smoothing_passes_ ? smoothing_change_sum_ / smoothing_passes_ : 0.0; }
  double max_smoothing_change() const { return max_smoothing_change_; }
  std::int64_t smoothing_passes() const { return smoothing_passes_; }
  /// The passes that fitted (all of them, but for the `reused` variant), and the memory its stored
  /// weights take now (0 for the other variants).
  std::int64_t smoothing_fits() const { return smoothing_fits_; }
  std::size_t mls_weight_bytes() const { return mls_weights_.bytes(); }

  /// Checkpoint/restart: the state besides the particles, and continuing from a saved one. The
  /// particles must be those of the saved solver, in its order (restore() keeps that order).
  SolverState state() const;
  /// How restore() rebuilds the cell sort: Exact, the saved blocks and order (the particles must be
  /// in the saved sort's order: a checkpoint of the same rank count), or Fresh, a new sort (a
  /// checkpoint written by another number of ranks). Collective in a distributed run.
  enum class RestoreSort { Exact, Fresh };
  void restore(ParticleStore particles, const SolverState& state, RestoreSort sort = RestoreSort::Exact);
  /// Distributed restart on the saved rank count: the saved slab bounds (before restore()).
  void set_slab_bounds(std::vector<int> first_columns) { decomposition_.set_first_columns(std::move(first_columns)); }
  /// Distributed restart on another rank count: new slab bounds balanced over `all` (every
  /// particle, the same on every rank), and the particles of `all` this rank owns.
  ParticleStore own_particles(ParticleStore all);

  /// Attach a work recorder (solver/work_recorder.hpp) or detach it (null, the default): the
  /// steps it asks for are timed region by region and block by block. Results are unchanged.
  void record_work(WorkRecorder* recorder) { recorder_ = recorder; }
  /// The order in which the passes over blocks hand them out (CellSort::set_block_order); the
  /// results are the same for either (tested), only the load balance differs.
  void set_block_order(BlockOrder order) { sort_.set_block_order(order); }

 private:
  template <class Terrain>
  void step_with_shape(double dt);
  template <class Shape, class Terrain>
  void step_with(double dt);
  // step_with's phases, in their order (solver.cpp says what each does).
  struct StepContext;     // what the phases of a step share: dt, gravity, the recorder, the tiles
  struct ScatteredNodes;  // what P2G hands the grid update
  void sort_if_due();
  StepContext step_context(double dt, double stress_dt, const Vec3& gravity);
  template <class Shape, class Terrain>
  ScatteredNodes scatter_phase(const StepContext& step);
  template <class Shape, class Terrain>
  ScatteredNodes scatter_stress_first_phase(const StepContext& step);
  void grid_phase(const StepContext& step, ScatteredNodes& p2g, bool remap);
  template <class Shape, class Terrain>
  TileStages gather_phase(const StepContext& step, bool remap);
  void take_gather_result(const GatherResult& r);
  const NodeVectors& remap_phase(const StepContext& step, TileStages& remap_stages);
  void move_phase(const StepContext& step);
  TileStages after_scatter(const StepContext& step, const char* name, ScatteredFields fields, bool clear_first = false);
  void clear_grid(const StepContext& step);
  template <class Shape, class Terrain>
  void update_stress(const NodeVectors& node_velocity, double dt, bool move);
  template <class Shape, class Terrain>
  void update_stress_smoothed(const NodeVectors& node_velocity, double dt, bool move);
  template <class Shape>
  double update_chunk(std::size_t begin, std::size_t end, const StrainIncrements& inc, double dt, bool move);
  template <class Shape, class FillChunk>
  void update_material_by_chunks(double dt, bool move, FillChunk fill);
  template <class Chunk>
  void for_blocks_in_chunks(const char* name, Chunk chunk);
  /// max over particles [begin, end) of c_p + |v_p| (0 for none; a NaN rate is skipped): in lanes
  /// when `rule` (every body's shared wave-speed rule) is given, else the scalar formula. Both give
  /// the same bits, and a maximum does not depend on how the particles are split.
  double max_wave_rate(std::size_t begin, std::size_t end, const WaveRateRule* rule) const;
  /// The rule for max_wave_rate: every body's shared rule when the vector kernels run, else none.
  std::optional<WaveRateRule> lanes_wave_rate_rule() const;
  void move_particles();
  /// The energy particle p holds: kinetic, stored strain, gravitational (energies(), the outflow).
  struct ParticleEnergy {
    double kinetic, strain, gravity;
  };
  ParticleEnergy particle_energy(std::size_t p) const;
  /// Its gravitational part, -m g.x (with the full g), which potential_energy() sums alone.
  double particle_potential(std::size_t p) const;
  /// Whether particle p is beyond an open face (the test G2P flags the step with).
  bool beyond_open_face(std::size_t p) const;
  /// How many particles are beyond an open face (after they moved): one parallel count.
  std::size_t count_outflow() const;
  /// Remove the `leaving` particles beyond an open face, adding their energy and mass to the
  /// outflow; deterministic (the kept particles keep their order). The caller sorts after it.
  void remove_outflow(std::size_t leaving);
  void wrap_periodic();
  /// Size the per-particle scratch arrays to the current particle count.
  void size_scratch();
  /// This step's displacement, in the scratch (valid from G2P until the next sort).
  std::array<std::span<double>, 3> displacement();
  /// The body force at time t: scene gravity, ramped over scene.gravity_ramp_time.
  Vec3 gravity_at(double t) const;
  /// The share of scene gravity at time t: t / gravity_ramp_time while it ramps, else 1.
  double gravity_ramp_factor(double t) const;
  /// -sum m g.x over this rank's particles, with the full g (the ledger's `gravity`); thread-independent.
  double potential_energy() const;
  void sort_particles();
  /// sort_particles(), recorded for the work record as its parallel loops (a static region) and its
  /// serial bookkeeping.
  void sort_particles_recorded();
  /// restore(): the time, the counters and the accumulated ledger.
  void restore_counters(const SolverState& s);
  /// The scalars of SolverState beside the members that hold them, one line each: f(member, saved)
  /// for each pair, so that state() and restore_counters() copy the same list, one way each.
  template <class Self, class State, class F>
  static void for_each_counter(Self& solver, State& s, F f);
  /// Distributed runs: move the slab bounds if the work is out of balance, and send every particle
  /// to the rank owning its cell (collective, at a sort).
  void redistribute();
  /// The particles per block column of the slab decomposition, summed over the ranks in rank order.
  std::vector<std::int64_t> particles_per_column() const;
  /// Sum the `scattered` node fields (mass, momentum, force: what the scatter wrote) on the tiles
  /// shared with other ranks (TileExchange); nothing in a serial run.
  void sum_shared_nodes(ScatteredFields scattered);
  [[noreturn]] void report_bad_particle(long long index, std::string_view what) const;

  Scene scene_;
  Comm comm_;
  SlabDecomposition decomposition_;
  TileExchange exchange_;
  bool collective_sort_ = false;   // this step: some rank must sort, so all do (with the migration)
  bool setup_exchange_ = false;    // this step: some rank's active tiles changed since the last setup
  bool tiles_changed_ = false;     // this rank sorted since the exchange was last set up
  double imbalance_ = 1.0, max_imbalance_ = 1.0;
  std::int64_t rebalances_ = 0, migrated_ = 0, exchange_bytes_ = 0;
  ParticleStore particles_;
  Grid grid_;
  CellSort sort_;
  Walls walls_;
  GhostMap ghosts_;  // walls_'s ghost nodes per tile, for the fold and the mirror
  double ghost_listing_seconds_ = 0.0;  // the last prepare_after_sort's listing of new tiles in ghosts_ (serial)
  BodyMaterials materials_;                   // the constitutive model of each body
  std::vector<double> block_dissipation_;     // per sort block, this step's material dissipation
  // The time step's maximum of c_p + |v_p|, taken per block at the end of the stress pass that ends
  // a step (MUSL, USL, USAVG: nothing changes v or V after it), while the particles are in cache;
  // the next step's time step uses it instead of a scan. Dropped by anything else that changes the
  // particles: outflow removal, a restore, migration, mutable access from outside.
  std::vector<double> block_wave_rate_;
  std::optional<double> wave_rate_from_stress_pass_;
  // Per-particle working memory lent to one phase at a time: the sort's keys and orders, then this
  // step's displacement dt sum N v^L (planes 0, 2, 4; written by G2P, applied after the strain pass).
  ParticleScratch scratch_;
  // solver.scatter = "block_buffers": the blocks' node boxes (prepared after every sort), else unused.
  BlockBuffers block_buffers_;
  BlockBuffers* block_buffers() { return scene_.scatter == ScatterOrder::BlockBuffers ? &block_buffers_ : nullptr; }
  void prepare_after_sort();  // the ghost map's new tiles and the block buffers' boxes
  double mass_floor_ = 0.0;
  double time_ = 0.0;
  std::int64_t step_ = 0;
  double last_dt_ = 0.0;
  bool needs_sort_ = true;
  int steps_since_sort_ = 0;
  double sort_drift_ = 0.0;  // SolverState::sort_drift: the sum of each step's largest displacement
  bool mls_needs_sort() const;
  std::int64_t sorts_ = 0;
  EnergyBudget work_;                  // the accumulated terms of the ledger (energy_budget.hpp)
  std::vector<double> block_damping_;  // per sort block, this step's PIC damping
  std::vector<double> tile_work_;      // per active tile, this step's wall friction work (add_grid_update)
  // output.energy_gap_terms: the accumulated terms, and this step's per tile and per block parts
  EnergyGapTerms gap_;
  std::vector<TileGapTerms> tile_gap_;
  std::vector<double> block_increment_kinetic_;
  void add_tile_gap_terms();
  double outflow_mass_ = 0.0;
  OutflowFaces outflow_faces_;           // SolverState::outflow_faces
  double periodic_gravity_shift_ = 0.0;  // SolverState::periodic_gravity_shift
  std::int64_t outflow_particles_ = 0;
  std::int64_t seeded_particles_ = 0;
  GatherOptions gather_limits_;            // the CFL limit and the open faces, for G2P's flags
  bool large_displacement_ = false;        // G2P of this step: some displacement beyond the limit
  bool crosses_open_face_ = false;         // G2P of this step: some particle leaves through an open face
  bool emptied_ = false;                   // every particle (on every rank) has left through the open faces
  PhaseTimes times_;
  // The work recorder (null unless attached) and its per-block timing buffers.
  WorkRecorder* recorder_ = nullptr;
  ColourPassTiming pass_timing_;
  std::vector<double> block_seconds_;        // the recorded loop's per-block times (for_blocks_in_chunks)
  std::vector<double> smooth_unit_seconds_;  // the MLS fit's per-unit times
  /// The recorder when the current step is recorded, else null.
  WorkRecorder* recording() const { return recorder_ && recorder_->active() ? recorder_ : nullptr; }
  // MLS smoothing: allocated only when the scene enables it.
  std::optional<MlsStrainSmoother> smoother_;
  std::vector<std::uint8_t> smooth_body_;                 // per body: smoothed or not
  std::array<std::vector<double>, 6> raw_strain_, smooth_strain_;  // per particle, this pass
  std::array<std::vector<double>, 3> raw_spin_;          // the spin stays unsmoothed
  MlsCounts last_smoothing_;
  std::int64_t unsmoothed_total_ = 0;
  std::int64_t guarded_total_ = 0;
  std::int64_t smoothing_passes_ = 0;
  double last_smoothing_change_ = 0.0, smoothing_change_sum_ = 0.0, max_smoothing_change_ = 0.0;
  void measure_smoothing_change();
  // MlsVariant::Reused: the weights of the last fit (empty: fit at the next pass), the strain summed
  // since (SolverState::mls_strain_since_fit), and each block's largest strain increment of this pass.
  MlsStoredWeights mls_weights_;
  double mls_strain_since_fit_ = 0.0;
  std::vector<double> block_max_strain_;
  std::vector<double> mls_rows_;  // MlsStoredWeights::apply's scratch
  std::int64_t smoothing_fits_ = 0;
};

}  // namespace talus
