#include "talus/solver/solver.hpp"

#include "talus/core/deterministic_sum.hpp"
#include "talus/core/error.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/core/tensor.hpp"
#include "talus/particles/particle_migration.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/shape/bspline.hpp"
#include "talus/shape/gimp.hpp"
#include "talus/shape/linear.hpp"
#include "talus/solver/grid_update.hpp"
#include "talus/solver/scheme.hpp"
#include "talus/solver/stability_guards.hpp"
#include "talus/transfer/transfers.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace talus {

namespace {

// The colour blocks must hold the widest support of the scene's shape function (cell_sort.hpp).
CellSort make_cell_sort(const Grid& grid, ShapeKind shape, int block_cells) {
  const ShapeReach reach = shape_reach(shape);
  return CellSort(grid, reach.low, reach.high, block_cells);
}

// Runs f(); when `recorder` is recording this step, adds it as a region of the given schedule
// (items: the loop length of a static region; regions: its parallel regions; barriers: those
// between its loops inside a region).
template <class F>
void recorded(WorkRecorder* recorder, RegionSchedule schedule, const char* name, std::size_t items, int regions, F&& f,
              int barriers = 0) {
  if (!recorder) {
    f();
    return;
  }
  const double start = omp_get_wtime();
  f();
  const double seconds = omp_get_wtime() - start;
  if (schedule == RegionSchedule::Serial)
    recorder->add_serial(name, seconds);
  else
    recorder->add_static(name, items, regions, seconds, barriers);
}

// Runs the stages of a grid phase (one parallel region), recorded as a static region over `tiles`.
void run_stages(WorkRecorder* recorder, const char* name, std::size_t tiles, const TileStages& stages) {
  if (stages.empty()) return;
  recorded(recorder, RegionSchedule::Static, name, tiles, 1, [&] { stages.run(); }, stages.loops() - 1);
}

// What a distributed run cannot do yet (Solver::check_ranks and the constructor).
void refuse_undistributable(const Scene& scene) {
  if (scene.smoothing.enabled)
    throw input_error("solver.smoothing.enabled = true: MLS smoothing is not available in a distributed run yet (its "
                      "neighbour search would need the particles of the next slab); run it on one rank");
  if (scene.grid.periodic[0])
    throw input_error("boundaries.x- = \"periodic\": a periodic x axis is not available in a distributed run yet (the "
                      "slabs cut x); run it on one rank");
}

// A restart's particles must be ones a step could have left (a damaged or edited checkpoint is
// refused here, before anything is written: a position beyond the padded grid crashed the sort).
// The same support test as G2P's "left the grid"; mass and volume positive; every id once.
void check_restored_particles(const ParticleStore& P, const Grid& grid, ShapeReach reach) {
  const GridGeometry& g = grid.geometry();
  const auto nodes = g.nodes();
  for (std::size_t p = 0; p < P.size(); ++p) {
    const double coords[3] = {P.x[0][p], P.x[1][p], grid.w_of(P.x[0][p], P.x[2][p])};
    for (int d = 0; d < 3; ++d) {
      const double t = std::floor(g.to_grid(d, coords[d]));  // compared as a double: no overflow
      if (!(t - reach.low >= 0.0 && t + reach.high < nodes[d]))
        throw io_error(fmt::format("restart: particle {} lies at ({:.6g}, {:.6g}, {:.6g}) m, outside the grid", P.id[p],
                                   P.x[0][p], P.x[1][p], P.x[2][p]));
    }
    if (!(P.mass[p] > 0.0 && std::isfinite(P.mass[p])) || !(P.volume[p] > 0.0 && std::isfinite(P.volume[p])))
      throw io_error(fmt::format("restart: particle {} has mass {:.6g} kg and volume {:.6g} m3; both must be positive and finite",
                                 P.id[p], P.mass[p], P.volume[p]));
  }
  // every field finite: a NaN velocity or stress stopped the first step, which then kept the same
  // state as the "last good state"
  P.for_each_double_array([&](const char* name, const ParticleArray<double>& a) {
    for (std::size_t p = 0; p < a.size(); ++p)
      if (!std::isfinite(a[p]))
        throw io_error(fmt::format("restart: particle {}'s {} is {}", P.id[p], name, a[p]));
  });
  std::vector<std::int64_t> ids(P.id.begin(), P.id.end());
  std::sort(ids.begin(), ids.end());
  if (const auto twice = std::adjacent_find(ids.begin(), ids.end()); twice != ids.end())
    throw io_error(fmt::format("restart: particle id {} is saved twice", *twice));
}

}  // namespace

void Solver::check_ranks(const Scene& scene, int ranks) {
  if (ranks <= 1) return;
  refuse_undistributable(scene);
  (void)SlabDecomposition(ranks, colour_block_edge(scene), particles_per_x_cell(scene));
}

Solver::Solver(Scene scene, Comm comm) : scene_(std::move(scene)), comm_(comm) {
  grid_ = Grid(scene_.grid);
  sort_ = make_cell_sort(grid_, scene_.shape, scene_.block_cells);
  if (comm_.distributed()) {
    // Slabs balanced over the seed points, then each rank seeds its own slab only (the ids are those
    // of a serial run: every point is counted, only the slab's are kept).
    refuse_undistributable(scene_);
    const std::vector<std::int64_t> per_cell = particles_per_x_cell(scene_);
    decomposition_ = SlabDecomposition(comm_.size(), sort_.block_cells(), per_cell);
    imbalance_ = max_imbalance_ = decomposition_.imbalance(decomposition_.work_per_column(per_cell));
    particles_ = seed_particles(scene_, [&](const Vec3& x) { return owner_of(x[0]) == comm_.rank(); });
    seeded_particles_ = static_cast<std::int64_t>(count_particles(scene_));
  } else {
    particles_ = seed_particles(scene_);
    seeded_particles_ = static_cast<std::int64_t>(particles_.size());
  }
  if (scene_.shape == ShapeKind::CpGimp) particles_.enable_domain_state();  // Edo & Matsubara 2015, eq. 57-58
  walls_ = Walls(scene_.walls, scene_.grid, grid_.profile_terrain());
  ghosts_ = GhostMap(walls_, grid_);
  materials_ = BodyMaterials(scene_, particles_);
  // Nodes lighter than this are empty: far below any real nodal mass, far above round-off. The
  // lightest particle of the scene: on every rank the same (a rank may hold none, or not the lightest).
  double lightest = std::numeric_limits<double>::infinity();
  for (double m : particles_.mass) lightest = std::min(lightest, m);
  mass_floor_ = 1e-12 * (comm_.distributed() ? comm_.min(lightest) : lightest);
  if (scene_.smoothing.enabled) {  // Edo & Matsubara 2015, eq. 54; buffers exist only for scenes that smooth
    smoother_.emplace(scene_.smoothing.mls, scene_.grid.h);
    smooth_body_.assign(scene_.bodies.size(), scene_.smoothing.bodies.empty() ? 1 : 0);
    for (int b : scene_.smoothing.bodies) smooth_body_[b] = 1;
  }
  size_scratch();
  // What G2P flags: a displacement beyond the CFL guard, a particle beyond an open face.
  gather_limits_.max_displacement = scene_.guards.max_step_displacement * scene_.grid.h;
  for (int d = 0; d < 3; ++d) {
    gather_limits_.lo[d] = scene_.grid.origin[d];
    gather_limits_.hi[d] = scene_.grid.origin[d] + scene_.grid.cells[d] * scene_.grid.h;
    for (int side = 0; side < 2; ++side) gather_limits_.open[d][side] = scene_.walls[d][side].type == WallType::Open;
  }
  sort_particles();
}

std::array<std::span<double>, 3> Solver::displacement() {
  const std::size_t n = particles_.size();
  return {scratch_.plane<double>(0, n), scratch_.plane<double>(2, n), scratch_.plane<double>(4, n)};
}

void Solver::size_scratch() {
  const std::size_t n = particles_.size();
  scratch_.reserve(n);
  if (smoother_) {
    for (int c = 0; c < 6; ++c) {
      raw_strain_[c].assign(n, 0.0);
      smooth_strain_[c].assign(n, 0.0);
    }
    for (auto& w : raw_spin_) w.assign(n, 0.0);
    // MlsStoredWeights::apply's rows, touched here rather than in the first step that reuses
    if (scene_.smoothing.mls.variant == MlsVariant::Reused) mls_rows_.assign(8 * n + 8, 0.0);
  }
}

// An open face lets material leave: a particle that has crossed one (it is past the face after
// this step's move) is removed, so sand can fall off the open side of a flume. The energy it
// carries (kinetic, stored strain, gravitational, as in energies()) and its mass are added to the
// outflow, so the energy budget still closes. G2P does not ask a leaving particle's next support to
// fit in the padded arrays (it has none): it may pass the 2 ghost cells when max_step_displacement > 1.
bool Solver::beyond_open_face(std::size_t p) const {
  const ParticleStore& P = particles_;
  const double point[3] = {P.x[0][p], P.x[1][p], grid_.w_of(P.x[0][p], P.x[2][p])};  // w on a terrain grid
  return gather_limits_.beyond_open_face(point);  // the test G2P flagged the step with
}

std::size_t Solver::count_outflow() const {
  const std::size_t n = particles_.size();
  std::size_t leaving = 0;
#pragma omp parallel for schedule(static) reduction(+ : leaving)
  for (std::size_t p = 0; p < n; ++p) leaving += beyond_open_face(p) ? 1 : 0;
  return leaving;
}

void Solver::remove_outflow(std::size_t leaving) {
  ParticleStore& P = particles_;
  const std::size_t n = P.size();
  wave_rate_from_stress_pass_.reset();  // the maximum included the particles that leave
  std::vector<std::uint32_t> kept;
  kept.reserve(n - leaving);
  for (std::size_t p = 0; p < n; ++p) {
    if (!beyond_open_face(p)) {
      kept.push_back(static_cast<std::uint32_t>(p));
      continue;
    }
    const ParticleEnergy e = particle_energy(p);
    work_.outflow += e.kinetic + e.strain + e.gravity;
    // Kept whether or not the gap's terms are written: the energy guard counts the potential energy
    // released by what left (outflow_gravity()).
    gap_.outflow_strain += e.strain;
    gap_.outflow_gravity += e.gravity;
    outflow_mass_ += P.mass[p];
    const double point[3] = {P.x[0][p], P.x[1][p], grid_.w_of(P.x[0][p], P.x[2][p])};  // as beyond_open_face
    outflow_faces_.add(outflow_face(gather_limits_, point), P.mass[p]);
    ++outflow_particles_;
  }
  P.permute(kept, scratch_, 0);  // the step's displacement is spent: the scratch is free
  size_scratch();
  mls_weights_.clear();  // the leavers were neighbours: the remaining fits no longer sum to 1
}

// A particle that left through a periodic face re-enters through the opposite one: its position
// moves by one period (GridGeometry::wrap_position, the map G2P used for its next cell). Its
// gravitational term -m g.x jumps by -m g.(x_wrapped - x) although nothing moved; the jumps are
// summed into periodic_gravity_shift_, which energies() adds back, so the `gravity` term is that of
// the unwrapped positions and the budget closes under gravity along a periodic axis (the tilted
// gravity of an inclined flow). Summed in fixed chunks: the same total for any thread count.
void Solver::wrap_periodic() {
  ParticleStore& P = particles_;
  const GridGeometry& g = scene_.grid;
  const Vec3& gravity = scene_.gravity;
  const auto shift = deterministic_sum<1>(P.size(), [&](std::size_t p, std::array<double, 1>& acc) {
    for (int d = 0; d < 2; ++d) {
      const double x = P.x[d][p], wrapped = g.wrap_position(d, x);
      if (wrapped == x) continue;
      P.x[d][p] = wrapped;
      acc[0] += P.mass[p] * gravity[d] * (wrapped - x);
    }
  });
  periodic_gravity_shift_ += shift[0];
}

// What a new sort invalidates or extends: the ghost map lists the tiles the flow reached since the
// last sort (serial, timed for the work record), and the block buffers size their boxes.
void Solver::prepare_after_sort() {
  const double listing_start = omp_get_wtime();
  ghosts_.list_active_tiles(walls_, grid_);
  ghost_listing_seconds_ = omp_get_wtime() - listing_start;
  if (block_buffers()) block_buffers_.prepare(sort_, grid_);
}

// The MLS neighbour search finds the particles through the cells they were sorted into; once some
// particle may have moved more than a quarter of a cell since the sort, sort again. Until then the
// search walks the cells within radius + drift (MlsStrainSmoother::smooth): at a quarter of a cell
// that is about the cells it walks right after a sort (particles at the quarter points of their
// cells, radius 1 or 2 cells), while a sort of every step cost 8-9% of a 1 M-particle step at a
// radius of 1 cell (docs/performance.md). The one-fit-per-cell variant evaluates the fit at the
// particles of each sorted cell, so it sorts every step.
bool Solver::mls_needs_sort() const {
  if (!smoother_) return false;
  if (scene_.smoothing.mls.variant == MlsVariant::Cell) return true;
  constexpr double kMaxDriftCells = 0.25;
  return !(sort_drift_ <= kMaxDriftCells * scene_.grid.h);  // NaN (never: G2P stops the run): sort
}

void Solver::sort_particles_recorded() {
  WorkRecorder* const r = recording();
  if (!r) {
    sort_particles();
    return;
  }
  const double start = omp_get_wtime();
  sort_particles();
  // serial: the sort's bookkeeping, the ghost map's new tiles, and the block buffers' serial
  // part of their preparation (the pairs of boxes and tiles; their run lists are written in parallel)
  const bool buffers = block_buffers() != nullptr;
  const double bookkeeping =
      sort_.last_serial_seconds() + ghost_listing_seconds_ + (buffers ? block_buffers_.last_serial_seconds() : 0.0);
  const double seconds = omp_get_wtime() - start, serial = std::min(bookkeeping, seconds);
  r->add_static("sort", particles_.size(),
                sort_.last_parallel_regions() + (buffers ? BlockBuffers::kPrepareParallelRegions : 0), seconds - serial);
  r->add_serial("sort bookkeeping", serial);
}

void Solver::sort_particles() {
  ScopedPhase timer(times_, Phase::Sort);
  ParticleArray<std::int64_t> ids_before;
  if (!mls_weights_.empty()) ids_before = particles_.id;
  sort_.sort(particles_, grid_, scratch_);
  if (!mls_weights_.empty()) mls_weights_.remap(ids_before, particles_.id);
  prepare_after_sort();
  needs_sort_ = false;
  steps_since_sort_ = 0;
  sort_drift_ = 0.0;
  ++sorts_;
  tiles_changed_ = true;
}

// ---- distributed runs (docs/architecture.md, "Distributed runs") ---------------------------------

std::vector<std::int64_t> Solver::particles_per_column() const {
  return comm_.sum_in_rank_order(decomposition_.particles_per_column(particles_.x[0], scene_.grid));
}

// The threshold of the rebalance: slabs move when the largest holds 10% more than the mean
// (SlabDecomposition::rebalance adds the hysteresis).
constexpr double kRebalanceThreshold = 1.10;

void Solver::redistribute() {
  const std::vector<std::int64_t> work = particles_per_column();
  if (decomposition_.rebalance(work, kRebalanceThreshold)) ++rebalances_;
  imbalance_ = decomposition_.imbalance(work);
  max_imbalance_ = std::max(max_imbalance_, imbalance_);
  const std::size_t n = particles_.size();
  std::vector<int> owner(n);
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p) owner[p] = owner_of(particles_.x[0][p]);
  wave_rate_from_stress_pass_.reset();  // other particles from here on
  migrated_ += static_cast<std::int64_t>(migrate_particles(comm_, particles_, owner));
  size_scratch();
}

void Solver::sum_shared_nodes(ScatteredFields scattered) {
  if (!comm_.distributed()) return;
  std::vector<NodeField> fields;
  if (scattered.mass) fields.push_back(grid_.mass);
  if (scattered.momentum) fields.insert(fields.end(), grid_.momentum.begin(), grid_.momentum.end());
  if (scattered.force) fields.insert(fields.end(), grid_.force.begin(), grid_.force.end());
  exchange_bytes_ += static_cast<std::int64_t>(exchange_.sum_shared(comm_, fields));
}

DistributionStats Solver::distribution() const {
  DistributionStats d;
  d.ranks = comm_.size();
  const auto sums = comm_.sum_in_rank_order(std::vector<std::int64_t>{
      static_cast<std::int64_t>(particles_.size()), exchange_bytes_, static_cast<std::int64_t>(exchange_.shared_tiles())});
  d.particles = sums[0];
  d.exchange_bytes = sums[1];
  d.shared_tiles = sums[2] / 2;
  d.imbalance = imbalance_;
  d.max_imbalance = max_imbalance_;
  d.rebalances = rebalances_;
  d.migrated = comm_.sum_in_rank_order(std::vector<std::int64_t>{migrated_})[0];
  return d;
}

std::int64_t Solver::outflow_particles() const { return comm_.sum_in_rank_order(std::vector<std::int64_t>{outflow_particles_})[0]; }
double Solver::outflow_mass() const { return comm_.sum_in_rank_order(outflow_mass_); }
double Solver::outflow_mass_x_plus() const { return comm_.sum_in_rank_order(outflow_faces_.mass[OutflowFaces::kXPlus]); }
OutflowFaces Solver::outflow_faces() const {
  OutflowFaces all;
  const std::vector<double> mass = comm_.sum_in_rank_order(std::vector<double>(outflow_faces_.mass.begin(), outflow_faces_.mass.end()));
  const std::vector<std::int64_t> count =
      comm_.sum_in_rank_order(std::vector<std::int64_t>(outflow_faces_.particles.begin(), outflow_faces_.particles.end()));
  std::copy(mass.begin(), mass.end(), all.mass.begin());
  std::copy(count.begin(), count.end(), all.particles.begin());
  return all;
}
double Solver::outflow_gravity() const { return comm_.sum_in_rank_order(gap_.outflow_gravity); }

bool Solver::finished() const {
  const bool time_done = time_ >= scene_.end_time * (1.0 - 1e-12);
  const bool steps_done = scene_.max_steps > 0 && step_ >= scene_.max_steps;
  return time_done || steps_done || emptied_;
}

bool Solver::stopped_at_max_steps() const {
  return scene_.max_steps > 0 && step_ >= scene_.max_steps && time_ < scene_.end_time * (1.0 - 1e-12) && !emptied_;
}

std::optional<WaveRateRule> Solver::lanes_wave_rate_rule() const {
  WaveRateRule rule;
  if (vector_kernels_enabled() && materials_.shared_wave_rate_rule(rule)) return rule;
  return std::nullopt;
}

double Solver::max_wave_rate(std::size_t begin, std::size_t end, const WaveRateRule* rule) const {
  const ParticleStore& P = particles_;
  if (rule) {
    // Every body has the same rule (the usual scene): the lanes do the scalar formula's arithmetic
    // per particle, and a maximum has no rounding, so the time step has the same bits.
    const WaveRateFields fields{P.volume.data(), P.volume0.data(), P.mass.data(), {P.v[0].data(), P.v[1].data(), P.v[2].data()}};
    return max_wave_rate_lanes(fields, *rule, begin, end);
  }
  double max_rate = 0.0;
  for (std::size_t p = begin; p < end; ++p) {
    const double volume = materials_.wave_speed_volume(P.body[p], P.volume[p], P.volume0[p]);
    const double c = std::sqrt(materials_.p_wave_modulus(P.body[p]) * volume / P.mass[p]);
    const double speed = std::sqrt(P.v[0][p] * P.v[0][p] + P.v[1][p] * P.v[1][p] + P.v[2][p] * P.v[2][p]);
    max_rate = std::max(max_rate, c + speed);
  }
  return max_rate;
}

double Solver::stable_time_step() const {
  const std::size_t n = particles_.size();
  const std::optional<WaveRateRule> rule = lanes_wave_rate_rule();
  const WaveRateRule* const lanes = rule ? &*rule : nullptr;
  constexpr std::size_t kChunk = 4096;
  const std::int64_t chunks = static_cast<std::int64_t>((n + kChunk - 1) / kChunk);
  double max_rate = 0.0;  // max (c_p + |v_p|)
#pragma omp parallel for schedule(static) reduction(max : max_rate)
  for (std::int64_t c = 0; c < chunks; ++c) {
    const std::size_t begin = static_cast<std::size_t>(c) * kChunk;
    max_rate = std::max(max_rate, max_wave_rate(begin, std::min(n, begin + kChunk), lanes));
  }
  return scene_.courant * scene_.grid.h / max_rate;  // Edo & Matsubara 2015, eq. 60
}

void Solver::step() {
  const bool recorded_step = recorder_ && recorder_->begin_step(step_, particles_.size(), sort_.block_count());
  const double step_start = recorded_step ? omp_get_wtime() : 0.0;
  double dt = 0.0;
  if (wave_rate_from_stress_pass_)  // the maximum the last stress pass kept: no scan, no parallel region
    dt = scene_.courant * scene_.grid.h / *wave_rate_from_stress_pass_;  // Edo & Matsubara 2015, eq. 60
  else
    recorded(recording(), RegionSchedule::Static, "time step", particles_.size(), 1, [&] { dt = stable_time_step(); });
  if (comm_.distributed()) {
    // One collective a step: the time step (the smallest; a min has the same bits in any order),
    // whether any rank must sort (then all sort and migrate), whether any rank's tiles changed.
    struct StepSync {
      double dt;
      std::int64_t particles;
      std::uint8_t sort, tiles_changed;
    };
    const StepSync mine{dt, static_cast<std::int64_t>(particles_.size()),
                        static_cast<std::uint8_t>(needs_sort_ || steps_since_sort_ >= scene_.sort_interval),
                        static_cast<std::uint8_t>(tiles_changed_)};
    std::int64_t particles = 0;
    collective_sort_ = setup_exchange_ = false;
    for (const StepSync& r : comm_.allgather(mine)) {
      dt = std::min(dt, r.dt);
      particles += r.particles;
      collective_sort_ = collective_sort_ || r.sort;
      setup_exchange_ = setup_exchange_ || r.tiles_changed;
    }
    if (particles == 0)
      throw instability_error(
          fmt::format("{}: every particle has left the grid through its open faces", step_started(step_, time_)));
  }
  if (!std::isfinite(dt) || dt <= 0.0)
    throw instability_error(fmt::format("{}: time step {} is not positive and finite", step_started(step_, time_), dt));
  const double remaining = scene_.end_time - time_;
  if (dt > remaining) dt = remaining;
  // While gravity ramps, the step's gravity is the share `ramp` of the full g whose potential the
  // ledger counts: book the rest of the potential it releases (EnergyBudget::gravity_ramp). Two
  // sums over the particles a step, and only while it ramps. (In a distributed run a particle that
  // migrates in the sort leaves one rank's sum for another's; over the ranks that cancels.)
  const double ramp = gravity_ramp_factor(time_ + 0.5 * dt);
  const double potential_before = ramp < 1.0 ? potential_energy() : 0.0;
  // The shape function and the terrain type are chosen here, once per step; the kernels below are
  // compiled for each pair, so a flat grid runs the FlatTerrain code with nothing extra.
  if (grid_.has_terrain())
    step_with_shape<ProfileTerrain>(dt);
  else
    step_with_shape<FlatTerrain>(dt);
  if (scene_.grid.has_periodic_axes()) recorded(recording(), RegionSchedule::Static, "wrap", particles_.size(), 1, [&] { wrap_periodic(); });
  if (ramp < 1.0) work_.gravity_ramp += (1.0 - ramp) * (potential_before - potential_energy());
  // G2P flagged these while it computed the displacements and the new positions; the scans that
  // name the particle (CFL guard) or remove the leaving ones run only when flagged.
  if (large_displacement_) check_step_displacement(particles_, displacement(), scene_, step_, time_);  // stability_guards.hpp
  // The outflow: a parallel count, then a serial rebuild, then a sort now: the cell offsets
  // describe the old particle set, and state() (a checkpoint, the last good state) reads them
  // before the next step would sort.
  if (crosses_open_face_) {
    std::size_t leaving = 0;
    recorded(recording(), RegionSchedule::Static, "outflow count", particles_.size(), 1, [&] { leaving = count_outflow(); });
    if (leaving > 0) {
      recorded(recording(), RegionSchedule::Serial, "outflow", 0, 0, [&] { remove_outflow(leaving); });
      sort_particles_recorded();
    }
  }
  // Nothing is left to move once every particle has left through the open faces: the run ends with
  // this step. A distributed run asks every rank (one collective a step, only with open faces).
  if (!comm_.distributed())
    emptied_ = particles_.size() == 0;
  else if (gather_limits_.has_open_face())
    emptied_ = !comm_.any(particles_.size() > 0);
  if ((step_ + 1) % kFieldCheckInterval == 0) {
    // one parallel region scans every particle array in use and the volume
    recorded(recording(), RegionSchedule::Static, "field check", particles_.size(), 1,
             [&] { check_particle_fields(particles_, scene_, step_, time_); });
  }
  time_ += dt;
  ++step_;
  last_dt_ = dt;
  if (recorded_step) recorder_->end_step(omp_get_wtime() - step_start);
}

template <class Terrain>
void Solver::step_with_shape(double dt) {
  switch (scene_.shape) {
    case ShapeKind::Linear: step_with<LinearShape, Terrain>(dt); break;
    case ShapeKind::UGimp: step_with<UGimpShape, Terrain>(dt); break;
    case ShapeKind::CpGimp: step_with<CpGimpShape, Terrain>(dt); break;
    case ShapeKind::BSpline2: step_with<QuadraticBSplineShape, Terrain>(dt); break;
  }
}

// What the phases of one step share (Solver::step_with): fixed once the sort has run, since the
// active tiles and the block buffers follow the sort. It lives on step_with's stack.
struct Solver::StepContext {
  double dt;
  double stress_dt;          // the scheme's share of dt for each stress update (scheme.hpp)
  Vec3 gravity;              // at the middle of the step (gravity_at: ramped)
  WorkRecorder* rec;         // the recorder when this step is recorded, else null
  ColourPassTiming* timing;  // the colour passes' per-block timing, when recorded
  std::size_t tiles;         // the active tiles
  BlockBuffers* buffers;     // solver.scatter = "block_buffers", else null
  // The grid is cleared before the first scatter of the step. With block buffers the scatter
  // writes only the boxes, so the clear can wait for the box sum, tile by tile, in its loop.
  bool clear_in_box_sum;
};

// What P2G hands the grid update: the node work queued after its last scatter (run in the grid
// phase's parallel region), and what that scatter wrote, which the grid update's ghost fold moves.
struct Solver::ScatteredNodes {
  TileStages stages;
  ScatteredFields folded;
};

// One explicit step, in the order MUSL runs it (Edo & Matsubara 2015, eq. 47-56); the scheme's row
// (solver/scheme.hpp) says which phases run and with what share of dt. Each phase is a member
// function below, in this order.
template <class Shape, class Terrain>
void Solver::step_with(double dt) {
  const SchemeSteps scheme = scheme_steps(scene_.scheme);
  const Vec3 gravity = gravity_at(time_ + 0.5 * dt);
  sort_if_due();  // 1. sort
  const StepContext step = step_context(dt, scheme.stress_dt_share * dt, gravity);
  // 2. P2G: nodal mass, momentum and internal force. USF / USAVG update the stress in between,
  //    from the start-of-step nodal velocities (walls applied), before scattering the force.
  ScatteredNodes p2g = scheme.stress_first ? scatter_stress_first_phase<Shape, Terrain>(step)
                                           : scatter_phase<Shape, Terrain>(step);
  grid_phase(step, p2g, scheme.remap);  // 3. grid
  // 4. G2P, with the remap's scatter in the same pass (MUSL, USAVG)
  TileStages remap_stages = gather_phase<Shape, Terrain>(step, scheme.remap);
  // 5. remap (MUSL, USAVG): the velocities the strain is computed from, else v^L
  const NodeVectors node_velocity =
      scheme.remap ? remap_phase(step, remap_stages) : grid_.lagrangian_velocity();
  // 6. strain (and its MLS smoothing when enabled) and stress, then move the particles (USF: only
  //    move them).
  if (scheme.stress_last)
    update_stress<Shape, Terrain>(node_velocity, step.stress_dt, true);
  else
    move_phase(step);
}

// 1. sort: when a particle has drifted beyond its block's slack, and every sort_interval steps
//    to keep the memory order close to the cell order. With MLS smoothing also when some particle
//    may have moved a quarter of a cell since the sort (mls_needs_sort). On several ranks every rank
//    sorts when one must (collective_sort_, from step()'s sync), and the shared tiles are found again.
// (recorded as its parallel loops, a static region, and its serial bookkeeping over the blocks)
void Solver::sort_if_due() {
  const bool sort_now = comm_.distributed()
                            ? collective_sort_
                            : mls_needs_sort() || needs_sort_ || steps_since_sort_ >= scene_.sort_interval;
  if (sort_now) {
    if (comm_.distributed()) recorded(recording(), RegionSchedule::Serial, "redistribute", 0, 0, [&] { redistribute(); });
    sort_particles_recorded();
  }
  if (comm_.distributed() && (sort_now || setup_exchange_)) {
    exchange_.setup(comm_, grid_);
    tiles_changed_ = false;
  }
  ++steps_since_sort_;
}

Solver::StepContext Solver::step_context(double dt, double stress_dt, const Vec3& gravity) {
  WorkRecorder* const rec = recording();
  BlockBuffers* const buffers = block_buffers();
  return {.dt = dt,
          .stress_dt = stress_dt,
          .gravity = gravity,
          .rec = rec,
          .timing = rec ? &pass_timing_ : nullptr,
          .tiles = grid_.active_tiles().size(),
          .buffers = buffers,
          .clear_in_box_sum = buffers && buffers->covers_active_tiles()};
}

// After a scatter: its record, and the stages of the node work that follows it, which the caller
// adds to and runs in one parallel region (run_stages). With block buffers the first stage is
// the sum of the boxes into the grid; on several ranks that sum runs on its own, so that the
// nodes the ranks share are summed across them (sum_shared_nodes) before the stages read them.
// `clear_first`: the box sum zeroes each tile before its sums (the step's grid clear, folded in).
TileStages Solver::after_scatter(const StepContext& step, const char* name, ScatteredFields fields,
                                 bool clear_first) {
  if (step.rec) step.rec->add_colour_passes(name, pass_timing_, sort_, step.buffers != nullptr);
  TileStages stages(step.tiles);
  if (step.buffers) step.buffers->add_sum_stage(stages, grid_, fields, clear_first);
  if (comm_.distributed()) {
    run_stages(step.rec, (std::string(name) + " box sum").c_str(), step.tiles, stages);
    stages = TileStages(step.tiles);
    sum_shared_nodes(fields);
  }
  return stages;
}

// The grid is cleared before the first scatter of the step (or in the box sum: StepContext).
void Solver::clear_grid(const StepContext& step) {
  if (!step.clear_in_box_sum)
    recorded(step.rec, RegionSchedule::Static, "grid clear", step.tiles, 1, [&] { grid_.clear_active(); });
}

// 2. P2G (MUSL, USL): nodal mass, momentum and internal force in one scatter. The node work after
//    it (the box sum, the ghost fold, the velocities and the mirror) runs as the stages of one
//    parallel region, timed in the grid phase.
template <class Shape, class Terrain>
Solver::ScatteredNodes Solver::scatter_phase(const StepContext& step) {
  ScopedPhase timer(times_, Phase::P2G);
  clear_grid(step);
  scatter_to_grid<Shape, Terrain>(particles_, sort_, grid_, ScatterFields::MassMomentumForce, step.timing,
                                  step.buffers);
  const ScatteredFields folded{.mass = true, .momentum = true, .force = true};
  return {after_scatter(step, "p2g", folded, step.clear_in_box_sum), folded};
}

// 2. P2G (USF, USAVG): mass and momentum, the start-of-step nodal velocities (walls applied), the
//    stress update from them, then the internal force from the updated stress.
template <class Shape, class Terrain>
Solver::ScatteredNodes Solver::scatter_stress_first_phase(const StepContext& step) {
  TileStages start_stages(step.tiles);
  {
    ScopedPhase timer(times_, Phase::P2G);
    clear_grid(step);
    scatter_to_grid<Shape, Terrain>(particles_, sort_, grid_, ScatterFields::MassMomentum, step.timing, step.buffers);
    start_stages = after_scatter(step, "p2g mass momentum", {.mass = true, .momentum = true}, step.clear_in_box_sum);
  }
  {
    ScopedPhase timer(times_, Phase::Grid);
    add_start_velocities(start_stages, grid_, walls_, ghosts_, step.gravity, mass_floor_);
    run_stages(step.rec, "start velocities", step.tiles, start_stages);
  }
  update_stress<Shape, Terrain>(grid_.start_velocity(), step.stress_dt, false);
  ScopedPhase timer(times_, Phase::P2G);
  scatter_to_grid<Shape, Terrain>(particles_, sort_, grid_, ScatterFields::Force, step.timing, step.buffers);
  const ScatteredFields folded{.force = true};
  return {after_scatter(step, "p2g force", folded), folded};
}

// 3. grid: velocities, accelerations with gravity, walls; the stages P2G queued run first, in the
// same parallel region. With a remap the grid update leaves the momentum at zero (ghost nodes
// included, and the mirror leaves it so) for the remap's scatter: one pass over the active tiles
// instead of two.
void Solver::grid_phase(const StepContext& step, ScatteredNodes& p2g, bool remap) {
  ScopedPhase timer(times_, Phase::Grid);
  const bool gap_terms = scene_.output.energy_gap_terms;
  add_grid_update(p2g.stages, grid_, walls_, ghosts_, p2g.folded, step.gravity, step.dt, mass_floor_, remap,
                  tile_work_, gap_terms ? &tile_gap_ : nullptr);
  run_stages(step.rec, "grid update", step.tiles, p2g.stages);
  work_.friction_work += counted_work(tile_work_, exchange_.counted());
  if (gap_terms) add_tile_gap_terms();
}

// 4. G2P: particle velocities and this step's displacement. MUSL and USAVG scatter the new
//    momentum for the remap in the same pass (the weights are those of x_p^k in both); the node
//    work after that scatter is returned for the remap (none without one).
template <class Shape, class Terrain>
TileStages Solver::gather_phase(const StepContext& step, bool remap) {
  TileStages remap_stages(step.tiles);
  ScopedPhase timer(times_, Phase::G2P);
  GatherOptions options = gather_limits_;
  options.dt = step.dt;
  options.pic_fraction = scene_.pic_fraction;
  options.remap = remap;
  if (options.pic_fraction > 0.0) block_damping_.assign(sort_.block_count(), 0.0);
  if (scene_.output.energy_gap_terms) {
    block_increment_kinetic_.assign(sort_.block_count(), 0.0);
    options.block_increment_kinetic = &block_increment_kinetic_;
  }
  const GatherResult r =
      gather_from_grid<Shape, Terrain>(particles_, sort_, grid_, displacement(), block_damping_, options, step.timing,
                                       remap ? step.buffers : nullptr);
  if (remap)
    remap_stages = after_scatter(step, "g2p", {.momentum = true});
  else if (step.rec)
    step.rec->add_colour_passes("g2p", pass_timing_, sort_, true);
  if (options.pic_fraction > 0.0)
    for (double d : block_damping_) work_.damping += d;  // in block order: thread-independent
  if (options.block_increment_kinetic)
    for (double k : block_increment_kinetic_) gap_.transfer_loss -= k;  // in block order
  take_gather_result(r);
  return remap_stages;
}

// What G2P found: a bad particle stops the step; the flags for the next sort, the MLS drift, the
// CFL guard and the outflow are kept.
void Solver::take_gather_result(const GatherResult& r) {
  if (r.nonfinite >= 0) report_bad_particle(r.nonfinite, "velocity is not finite");
  if (r.outside >= 0) {
    // (the position alone is the one before the step, still inside: where this step takes it says why)
    const auto q = static_cast<std::size_t>(r.outside);
    const std::array<std::span<double>, 3> dx = displacement();
    report_bad_particle(r.outside, fmt::format("left the grid (this step moves it to ({:.6g}, {:.6g}, {:.6g}) m)",
                                               particles_.x[0][q] + dx[0][q], particles_.x[1][q] + dx[1][q],
                                               particles_.x[2][q] + dx[2][q]));
  }
  needs_sort_ = r.needs_sort;
  // Counted before the move, so the drift the smoother allows for already holds this step's
  // (larger than needed until the move; never smaller).
  sort_drift_ += std::sqrt(r.max_displacement2);
  large_displacement_ = r.large_displacement;
  crosses_open_face_ = r.crosses_open_face;
}

// 5. remap (MUSL): v_i^{k+1} = sum m_p v_p N_i / m_i, with the walls (Edo & Matsubara 2015, eq. 52); the
//    momentum was scattered in the G2P pass. Returns the remapped velocities.
const NodeVectors& Solver::remap_phase(const StepContext& step, TileStages& remap_stages) {
  ScopedPhase timer(times_, Phase::Remap);
  add_velocities_from_momentum(remap_stages, grid_, walls_, ghosts_, step.gravity, mass_floor_);
  run_stages(step.rec, "remap grid", step.tiles, remap_stages);
  return grid_.velocity();
}

// 6. (USF) no stress update at the end of the step: only the move, x_p += the step's displacement.
void Solver::move_phase(const StepContext& step) {
  ScopedPhase timer(times_, Phase::Stress);
  recorded(step.rec, RegionSchedule::Static, "move", particles_.size(), 1, [&] { move_particles(); });
}

void Solver::check_particles() const { check_particle_fields(particles_, scene_, step_ - 1, time_ - last_dt_); }

double Solver::gravity_ramp_factor(double t) const {
  return scene_.gravity_ramp_time <= 0.0 || t >= scene_.gravity_ramp_time ? 1.0 : t / scene_.gravity_ramp_time;
}

Vec3 Solver::gravity_at(double t) const {
  const double factor = gravity_ramp_factor(t);
  return factor == 1.0 ? scene_.gravity : scene_.gravity * factor;
}

double Solver::potential_energy() const {
  const auto sum = deterministic_sum<1>(particles_.size(), [&](std::size_t p, std::array<double, 1>& acc) {
    acc[0] += particle_potential(p);
  });
  return sum[0] + periodic_gravity_shift_;  // the unwrapped positions' potential, as energies() counts it
}

void Solver::move_particles() {
  ParticleStore& P = particles_;
  const std::size_t n = P.size();
  const std::array<std::span<double>, 3> dx = displacement();
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p)
    for (int d = 0; d < 3; ++d) P.x[d][p] += dx[d][p];
}

// Strain increments are gathered for a chunk of particles into a small buffer, then the material
// update runs over the chunk: the gather stays cache-friendly and the update loop is simple.
// The dissipated energy is summed per block, then over blocks in block order, so the total does
// not depend on the thread count.
// cpGIMP domains follow the deformation here too (Edo & Matsubara 2015, eq. 57-58). `move` applies the step's
// displacement afterwards (the particles' last use of their start-of-step position).
template <class Shape, class Terrain>
void Solver::update_stress(const NodeVectors& node_velocity, double dt, bool move) {
  if (smoother_) {
    update_stress_smoothed<Shape, Terrain>(node_velocity, dt, move);
    return;
  }
  ScopedPhase timer(times_, Phase::Stress);
  update_material_by_chunks<Shape>(dt, move, [&](std::size_t begin, std::size_t end, StrainIncrements& inc) {
    strain_increments<Shape, Terrain>(particles_, grid_, node_velocity, dt, begin, end, inc);
  });
}

// One parallel loop over the sort blocks, heaviest first (schedule(dynamic, 1)), each block in chunks
// of at most StrainIncrements::kCapacity particles: chunk(b, begin, end, inc) with a thread's own
// increments buffer. A recorded step records the loop as `name` with each block's time.
template <class Chunk>
void Solver::for_blocks_in_chunks(const char* name, Chunk chunk) {
  const std::size_t blocks = sort_.block_count();
  WorkRecorder* const rec = recording();
  if (rec) block_seconds_.assign(blocks, 0.0);
  const double pass_start = rec ? omp_get_wtime() : 0.0;
#pragma omp parallel
  {
    StrainIncrements inc;
    const std::vector<std::uint32_t>& order = sort_.blocks_in_work_order();
#pragma omp for schedule(dynamic, 1)
    for (std::size_t bi = 0; bi < blocks; ++bi) {
      const std::size_t b = order[bi];
      const double block_start = rec ? omp_get_wtime() : 0.0;
      for (std::size_t begin = sort_.block_begin(b); begin < sort_.block_end(b); begin += StrainIncrements::kCapacity)
        chunk(b, begin, std::min<std::size_t>(begin + StrainIncrements::kCapacity, sort_.block_end(b)), inc);
      if (rec) block_seconds_[bi] = omp_get_wtime() - block_start;
    }
  }
  if (rec) rec->add_block_loop(name, block_seconds_, omp_get_wtime() - pass_start, sort_);
}

// The material update over chunks of StrainIncrements::kCapacity particles, parallel over sort
// blocks: fill(begin, end, inc) provides the chunk's strain and spin increments. The dissipation
// is summed per block, then over blocks in block order, so it does not depend on the thread count.
template <class Shape, class FillChunk>
void Solver::update_material_by_chunks(double dt, bool move, FillChunk fill) {
  const std::size_t blocks = sort_.block_count();
  block_dissipation_.assign(blocks, 0.0);
  // The pass that moves the particles ends the step (MUSL, USL, USAVG): after it nothing changes
  // v or V, so the next time step's maximum is taken here, per chunk, while the chunk is in cache.
  const bool keep_wave_rate = move;
  const std::optional<WaveRateRule> rule = keep_wave_rate ? lanes_wave_rate_rule() : std::nullopt;
  const WaveRateRule* const lanes = rule ? &*rule : nullptr;
  wave_rate_from_stress_pass_.reset();
  if (keep_wave_rate) block_wave_rate_.assign(blocks, 0.0);
  // the blocks' sums start from the zeros assigned above, chunk by chunk in order: thread-independent
  for_blocks_in_chunks("stress", [&](std::size_t b, std::size_t begin, std::size_t end, StrainIncrements& inc) {
    fill(begin, end, inc);
    block_dissipation_[b] += update_chunk<Shape>(begin, end, inc, dt, move);
    if (keep_wave_rate) block_wave_rate_[b] = std::max(block_wave_rate_[b], max_wave_rate(begin, end, lanes));
  });
  for (double d : block_dissipation_) work_.plastic_work += d;
  if (keep_wave_rate) {
    double max_rate = 0.0;
    for (double r : block_wave_rate_) max_rate = std::max(max_rate, r);
    wave_rate_from_stress_pass_ = max_rate;
  }
}

// The material update of particles [begin, end) from their increments; returns the dissipation.
template <class Shape>
double Solver::update_chunk(std::size_t begin, std::size_t end, const StrainIncrements& inc, double dt, bool move) {
  ParticleStore& P = particles_;
  const double dissipated = materials_.update(P, begin, end, inc, dt);
  if constexpr (Shape::kDomain == DomainSource::Current) {
    // Edo & Matsubara 2015, eq. 57-58, l_p = G_p l_p0 with G_p <- (I + grad v dt) G_p, for a domain kept
    // as an axis-aligned box: each half width stretches with the normal strain increment
    // along its axis, l_d <- (1 + d_eps_dd) l_d (the shear part of G would tilt the box).
    for (std::size_t p = begin; p < end; ++p)
      for (int d = 0; d < 3; ++d) P.domain[d][p] *= 1.0 + inc.strain[d][p - begin];
  }
  if (move) {
    const std::array<std::span<double>, 3> dx = displacement();
    for (std::size_t p = begin; p < end; ++p)
      for (int d = 0; d < 3; ++d) P.x[d][p] += dx[d][p];
  }
  return dissipated;
}

// With MLS smoothing (Edo & Matsubara 2015, eq. 53-56) a particle's fit needs its neighbours' increments, so
// the increments of all particles are computed first into full arrays, then smoothed, then the
// material update runs per chunk with the smoothed strain increments (the spin is not smoothed:
// it only rotates the stress, eq. 54 names the strain). Positions move in the last pass, after
// the smoother has read them.
template <class Shape, class Terrain>
void Solver::update_stress_smoothed(const NodeVectors& node_velocity, double dt, bool move) {
  ParticleStore& P = particles_;
  WorkRecorder* const rec = recording();
  const bool reused = scene_.smoothing.mls.variant == MlsVariant::Reused;
  // The reused variant's largest strain increment: a NaN wins, so that the next pass fits.
  auto larger_or_nan = [](double a, double b) { return b > a || b != b ? b : a; };
  {
    ScopedPhase timer(times_, Phase::Stress);
    if (reused) block_max_strain_.assign(sort_.block_count(), 0.0);
    for_blocks_in_chunks("mls strain", [&](std::size_t b, std::size_t begin, std::size_t end, StrainIncrements& inc) {
      strain_increments<Shape, Terrain>(P, grid_, node_velocity, dt, begin, end, inc);  // eq. 53
      for (int c = 0; c < 6; ++c) std::copy_n(inc.strain[c].data(), end - begin, raw_strain_[c].data() + begin);
      for (int c = 0; c < 3; ++c) std::copy_n(inc.spin[c].data(), end - begin, raw_spin_[c].data() + begin);
      if (reused) {  // the largest squared Frobenius norm (tensor components: the shear ones count twice)
        double largest = block_max_strain_[b];
        for (std::size_t i = 0; i < end - begin; ++i) {
          double n2 = 0.0;
          for (int c = 0; c < 6; ++c) n2 += (c < 3 ? 1.0 : 2.0) * inc.strain[c][i] * inc.strain[c][i];
          largest = larger_or_nan(largest, n2);
        }
        block_max_strain_[b] = largest;
      }
    });
  }
  {
    ScopedPhase timer(times_, Phase::Smooth);  // eq. 54
    std::array<const double*, 6> in;
    std::array<double*, 6> out;
    for (int c = 0; c < 6; ++c) {
      in[c] = raw_strain_[c].data();
      out[c] = smooth_strain_[c].data();
    }
    // The search widens by the drift since the sort (mls_needs_sort).
    const double smooth_start = rec ? omp_get_wtime() : 0.0;
    // The `reused` variant fits when it has no weights (the first pass, or after a particle left)
    // or the material has strained by reuse_strain since the fit; otherwise it applies the weights.
    const bool fits = !(reused && !mls_weights_.empty() && mls_strain_since_fit_ <= scene_.smoothing.mls.reuse_strain);
    if (fits) {
      last_smoothing_ = smoother_->smooth(P, sort_, scene_.grid, in, out, smooth_body_, sort_drift_,
                                          rec ? &smooth_unit_seconds_ : nullptr, reused ? &mls_weights_ : nullptr);
      mls_strain_since_fit_ = 0.0;
      ++smoothing_fits_;
      if (rec)
        rec->add_unit_loop("mls smooth", smooth_unit_seconds_, MlsStrainSmoother::work_unit_particles(sort_),
                           omp_get_wtime() - smooth_start);
    } else {
      last_smoothing_ = mls_weights_.apply(in, out, P.body, smooth_body_, mls_rows_);
      if (rec) rec->add_static("mls reuse", P.size(), 1, omp_get_wtime() - smooth_start);
    }
    // This pass's strain moves the particles away from the positions the weights were fitted at.
    if (reused) {
      double largest = 0.0;
      for (double n2 : block_max_strain_) largest = larger_or_nan(largest, n2);
      mls_strain_since_fit_ += std::sqrt(largest);
    }
    unsmoothed_total_ += static_cast<std::int64_t>(last_smoothing_.unsmoothed);
    guarded_total_ += static_cast<std::int64_t>(last_smoothing_.smoothed + last_smoothing_.unsmoothed);
    recorded(rec, RegionSchedule::Static, "mls change", P.size(), 1, [&] { measure_smoothing_change(); });
  }
  ScopedPhase timer(times_, Phase::Stress);
  update_material_by_chunks<Shape>(dt, move, [&](std::size_t begin, std::size_t end, StrainIncrements& inc) {
    for (int c = 0; c < 6; ++c) std::copy_n(smooth_strain_[c].data() + begin, end - begin, inc.strain[c].data());
    for (int c = 0; c < 3; ++c) std::copy_n(raw_spin_[c].data() + begin, end - begin, inc.spin[c].data());
  });  // eq. 55-56
}

// deterministic_sum: the same value for any thread count.
void Solver::measure_smoothing_change() {
  const auto sums = deterministic_sum<2>(particles_.size(), [&](std::size_t p, std::array<double, 2>& acc) {
    for (int c = 0; c < 6; ++c) {
      const double raw = raw_strain_[c][p], change = smooth_strain_[c][p] - raw;
      acc[0] += raw * raw;
      acc[1] += change * change;
    }
  });
  last_smoothing_change_ = sums[0] > 0.0 ? std::sqrt(sums[1] / sums[0]) : 0.0;
  smoothing_change_sum_ += last_smoothing_change_;
  max_smoothing_change_ = std::max(max_smoothing_change_, last_smoothing_change_);
  ++smoothing_passes_;
}

Solver::ParticleEnergy Solver::particle_energy(std::size_t p) const {
  const ParticleStore& P = particles_;
  const double v2 = P.v[0][p] * P.v[0][p] + P.v[1][p] * P.v[1][p] + P.v[2][p] * P.v[2][p];
  Sym6 s;
  for (int c = 0; c < 6; ++c) s[c] = P.stress[c][p];
  return {0.5 * P.mass[p] * v2, P.volume[p] * materials_.stored_energy_density(P.body[p], s), particle_potential(p)};
}

double Solver::particle_potential(std::size_t p) const {
  const ParticleStore& P = particles_;
  const Vec3& g = scene_.gravity;
  return -P.mass[p] * (g[0] * P.x[0][p] + g[1] * P.x[1][p] + g[2] * P.x[2][p]);
}

EnergyBudget Solver::energies() const {
  const auto sums = deterministic_sum<3>(particles_.size(), [&](std::size_t p, std::array<double, 3>& acc) {
    const ParticleEnergy e = particle_energy(p);
    acc[0] += e.kinetic;
    acc[1] += e.strain;
    acc[2] += e.gravity;
  });
  EnergyBudget e = work_;
  e.kinetic = sums[0];
  e.strain = sums[1];
  e.gravity = sums[2] + periodic_gravity_shift_;  // the unwrapped positions' potential (wrap_periodic)
  if (!comm_.distributed()) return e;
  // Each rank's ledger, added in rank order: the same bits on every rank and in every run.
  std::vector<double> terms;
  EnergyBudget::for_each_term(e, [&](const char*, double value, bool) { terms.push_back(value); });
  const std::vector<double> total = comm_.sum_in_rank_order(terms);
  std::size_t i = 0;
  EnergyBudget::for_each_term(e, [&](const char*, double& value, bool) { value = total[i++]; });
  return e;
}

// The grid update's per-tile energy gap terms, added in tile order (thread-independent); in a
// distributed run only the tiles this rank counts (a shared tile once, as the wall work).
void Solver::add_tile_gap_terms() {
  const std::vector<std::uint8_t>& counted = exchange_.counted();
  for (std::size_t t = 0; t < tile_gap_.size(); ++t) {
    if (!counted.empty() && !counted[t]) continue;
    const TileGapTerms& g = tile_gap_[t];
    gap_.grid_stress_work += g.stress_work;
    gap_.grid_wall_work += g.wall_work;
    gap_.grid_gravity_work += g.gravity_work;
    gap_.transfer_loss += g.increment_kinetic;
  }
}

EnergyGapTerms Solver::energy_gap_terms() const {
  if (!comm_.distributed()) return gap_;
  std::vector<double> terms;
  EnergyGapTerms::for_each_term(gap_, [&](const char*, double value) { terms.push_back(value); });
  const std::vector<double> total = comm_.sum_in_rank_order(terms);
  EnergyGapTerms sum;
  std::size_t i = 0;
  EnergyGapTerms::for_each_term(sum, [&](const char*, double& value) { value = total[i++]; });
  return sum;
}

void Solver::report_bad_particle(long long index, std::string_view what) const {
  const auto p = static_cast<std::size_t>(index);
  const ParticleStore& P = particles_;
  throw instability_error(fmt::format(
      "{}: particle {} (body \"{}\") {}: position ({:.6g}, {:.6g}, {:.6g}) m, velocity ({:.6g}, "
      "{:.6g}, {:.6g}) m/s",
      step_started(step_, time_), P.id[p], scene_.bodies[P.body[p]].name, what, P.x[0][p], P.x[1][p], P.x[2][p], P.v[0][p],
      P.v[1][p], P.v[2][p]));
}

// ---- checkpoint/restart (docs/reliability.md) ----------------------------------------------------

template <class Self, class State, class F>
void Solver::for_each_counter(Self& solver, State& s, F f) {
  f(solver.time_, s.time);
  f(solver.step_, s.step);
  f(solver.last_dt_, s.last_dt);
  f(solver.work_, s.work);
  f(solver.gap_, s.gap);
  f(solver.outflow_mass_, s.outflow_mass);
  f(solver.outflow_faces_, s.outflow_faces);
  f(solver.outflow_particles_, s.outflow_particles);
  f(solver.steps_since_sort_, s.steps_since_sort);
  f(solver.sorts_, s.sorts);
  f(solver.needs_sort_, s.needs_sort);
  f(solver.periodic_gravity_shift_, s.periodic_gravity_shift);
  f(solver.sort_drift_, s.sort_drift);
}

SolverState Solver::state() const {
  SolverState s;
  for_each_counter(*this, s, [](const auto& member, auto& saved) { saved = member; });
  if (!mls_weights_.empty())  // a view (SolverState::mls_weights)
    s.mls_weights = std::shared_ptr<const MlsStoredWeights>(std::shared_ptr<const MlsStoredWeights>(), &mls_weights_);
  s.mls_strain_since_fit = mls_strain_since_fit_;
  // The cell each particle was sorted into, read back from the sort's block and cell offsets.
  const std::size_t n = particles_.size();
  for (auto& c : s.sort_cell) c.resize(n);  // every particle lies in one cell: every entry is written below
  const int bc = sort_.block_cells();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  const auto& cell_start = sort_.cell_start();
  const std::size_t blocks = sort_.block_count();
  // (each block writes its own particles: parallel, as the run loop's snapshot takes it every few steps)
#pragma omp parallel for schedule(static)
  for (std::size_t b = 0; b < blocks; ++b) {
    const auto o = sort_.block_origin(b);
    for (std::size_t l = 0; l < cells_per_block; ++l) {
      const int li = static_cast<int>(l / (bc * bc)), lj = static_cast<int>((l / bc) % bc), lk = static_cast<int>(l % bc);
      for (std::uint32_t p = cell_start[b * cells_per_block + l]; p < cell_start[b * cells_per_block + l + 1]; ++p) {
        s.sort_cell[0][p] = o[0] + li;
        s.sort_cell[1][p] = o[1] + lj;
        s.sort_cell[2][p] = o[2] + lk;
      }
    }
  }
  return s;
}

ParticleStore Solver::own_particles(ParticleStore all) {
  if (!comm_.distributed()) return all;
  decomposition_.set_first_columns(SlabDecomposition::balanced_first_columns(
      decomposition_.particles_per_column(all.x[0], scene_.grid), comm_.size()));
  std::vector<std::uint32_t> mine;
  for (std::size_t p = 0; p < all.size(); ++p)
    if (owner_of(all.x[0][p]) == comm_.rank()) mine.push_back(static_cast<std::uint32_t>(p));
  all.permute(mine);
  return all;
}

void Solver::restore(ParticleStore particles, const SolverState& s, RestoreSort mode) {
  const std::size_t n = particles.size();
  // Fewer particles than the scene seeds: the others left through open faces (remove_outflow).
  const std::vector<std::int64_t> counts =
      comm_.sum_in_rank_order(std::vector<std::int64_t>{static_cast<std::int64_t>(n), s.outflow_particles});
  if (counts[0] + counts[1] != seeded_particles_)
    throw io_error(fmt::format("restart: {} particles saved and {} left through open faces, the scene seeds {}", counts[0],
                               counts[1], seeded_particles_));
  // Each rank checks its own particles; one that refuses them must not leave the others waiting in
  // the sort's collectives (Comm::agree).
  comm_.agree([&] {
    if (mode == RestoreSort::Exact)
      for (const auto& c : s.sort_cell)
        if (c.size() != n) throw io_error("restart: the saved sort state does not match the particles");
    const ShapeReach reach = shape_reach(scene_.shape);
    check_restored_particles(particles, grid_, reach);
    if (mode == RestoreSort::Exact) {
      const auto nodes = scene_.grid.nodes();
      for (std::size_t p = 0; p < n; ++p)
        for (int d = 0; d < 3; ++d)
          if (s.sort_cell[d][p] - reach.low < 0 || s.sort_cell[d][p] + reach.high >= nodes[d])
            throw io_error(fmt::format("restart: particle {}'s saved sort cell ({}, {}, {}) lies outside the grid",
                                       particles.id[p], s.sort_cell[0][p], s.sort_cell[1][p], s.sort_cell[2][p]));
    }
  });
  particles_ = std::move(particles);
  emptied_ = counts[0] == 0;
  wave_rate_from_stress_pass_.reset();
  size_scratch();
  if (mode == RestoreSort::Fresh) {
    restore_counters(s);
    sort_particles();
    return;
  }
  // Rebuild the cell sort exactly as the saved solver had it: sort with every particle placed at
  // the centre of its saved cell. The particles are already in that key order, so the (stable)
  // sort keeps their order and rebuilds the same blocks, colours and active tiles.
  std::array<ParticleArray<double>, 3> x;
  for (int d = 0; d < 3; ++d) {
    x[d] = particles_.x[d];
    for (std::size_t p = 0; p < n; ++p) particles_.x[d][p] = scene_.grid.node_position(d, s.sort_cell[d][p]) + 0.5 * scene_.grid.h;
  }
  // On a terrain grid the cell centre's w maps to z = w + z_b(x) (the sort maps it back).
  if (grid_.has_terrain())
    for (std::size_t p = 0; p < n; ++p) particles_.x[2][p] = grid_.z_of(particles_.x[0][p], particles_.x[2][p]);
  const ParticleArray<std::int64_t> ids = particles_.id;
  sort_.sort(particles_, grid_, scratch_);
  prepare_after_sort();
  comm_.agree([&] {
    if (particles_.id != ids) throw io_error("restart: the saved particle order is not the saved sort's order");
  });
  particles_.x = std::move(x);
  tiles_changed_ = true;
  restore_counters(s);
}

void Solver::restore_counters(const SolverState& s) {
  for_each_counter(*this, s, [](auto& member, const auto& saved) { member = saved; });
  if (!s.mls_weights || s.mls_weights->particle_count() != particles_.size())
    mls_weights_.clear();
  else if (s.mls_weights.get() != &mls_weights_)
    mls_weights_ = *s.mls_weights;
  mls_strain_since_fit_ = s.mls_strain_since_fit;
}

}  // namespace talus
