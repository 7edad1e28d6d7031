#pragma once
// Runout diagnostics of a granular flow down a flume (docs/flume.md "Runout diagnostics"). All
// positions are along the flume coordinate s (FlumeCoordinates: arc length on a terrain, x when flat).
//
// Front and tail are mass quantiles, so that a few stray particles do not move them: with the
// particles ordered by s (ties by id) and C_k the mass of the first k of them, the q-quantile is the
// s of the first particle with C_k >= q M. front = quantile(front_quantile = 0.995),
// tail = quantile(tail_quantile = 0.005). The extremes s_min, s_max are reported alongside.
//
// Everything is summed in that (s, id) order, serially: the numbers do not depend on the thread
// count nor on the order of the particle store.
#include "talus/diagnostics/flume_coordinates.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace talus {

struct RunoutSample {
  double time = 0.0;
  std::int64_t step = 0;
  double mass = 0.0;               // total particle mass [kg]
  double front = 0.0, tail = 0.0;  // mass quantiles of s [m]
  double s_min = 0.0, s_max = 0.0; // the rearmost and foremost particle [m]
  double centre_s = 0.0;           // mass-weighted mean of s [m]
  Vec3 centre = Vec3::Zero();      // centre of mass (x, y, z) [m]
  double centre_velocity_s = 0.0;  // mass-weighted mean of v . t(x): the momentum along the bed / M [m/s]
  double front_velocity = 0.0;     // (front - previous front) / (time - previous time) [m/s]; 0 for the first
  /// Where the front and tail lie (locate_front_and_tail): x at their s, and the bed's height z there
  /// on a terrain. NaN for z on a flat grid (s = x, the bed is no profile), and for all four when no
  /// particle is left.
  double front_x = 0.0, front_z = 0.0, tail_x = 0.0, tail_z = 0.0;
};

/// Fills the sample's front_x, front_z, tail_x, tail_z from its front and tail (s). measure_runout
/// calls it; a restart calls it for rows read back from a runout.csv written before these columns.
void locate_front_and_tail(RunoutSample& sample, const FlumeCoordinates& coordinates);

/// One sample of the particle set (front_velocity left 0; RunoutMonitor fills it in). With no particle
/// left (all went through the open faces) the mass is 0 and every position and velocity is NaN.
RunoutSample measure_runout(const ParticleStore& particles, const FlumeCoordinates& coordinates,
                            double front_quantile, double tail_quantile);
/// The parallel regions measure_runout opens for n particles on `threads` threads: its two loops and
/// its sort's (the work recorder counts them, talus run --record-work).
int measure_runout_regions(std::size_t n, int threads);

/// The deposit thickness on the bed: a raster of cells ds x dy in (s, y); thickness = the particle
/// volume (current volume V_p) whose s and y fall in the cell, divided by the cell's bed area ds dy.
/// For a uniform layer that is its bed-normal thickness. `seeded_thickness` sums the particles' seeded
/// volumes V_p0 = m_p / rho_0 instead: the thickness the same mass makes at the density it was seeded
/// with. (A flowing sand loosens in MPM: the flume's deposit ends 31% above its seeded volume,
/// docs/flume.md "The sand loosens as it flows".) Cell (i, j) covers
/// [s0 + i ds, s0 + (i + 1) ds) x [y0 + j dy, y0 + (j + 1) dy).
struct DepositRaster {
  double s0 = 0.0, ds = 0.0, y0 = 0.0, dy = 0.0;
  int ns = 0, ny = 0;
  std::vector<double> thickness;         // ns * ny, index i * ny + j
  std::vector<double> seeded_thickness;  // the same with the seeded volumes
  double volume_outside = 0.0;    // particle volume outside the raster [m^3]
  double at(int i, int j) const { return thickness[static_cast<std::size_t>(i) * ny + j]; }
  double seeded_at(int i, int j) const { return seeded_thickness[static_cast<std::size_t>(i) * ny + j]; }
  double s_centre(int i) const { return s0 + (i + 0.5) * ds; }
  double y_centre(int j) const { return y0 + (j + 0.5) * dy; }
};

/// Raster over [s0, s1) x [y0, y1) with square cells of about `cell` (whole numbers of cells that
/// cover the range). Particles are added in id order (independent of the store's order).
DepositRaster measure_deposit(const ParticleStore& particles, const FlumeCoordinates& coordinates, double s0,
                              double s1, double y0, double y1, double cell);

/// The final runout: the front at the end of the run, measured from the gate and from the start of
/// the runout plane (where known).
struct RunoutResult {
  // How the run ended (RunoutFiles::finish sets them): run.json's status (completed, interrupted,
  // unstable), and final only when it reached time.end. An interrupted run's result is its state
  // where it stopped; a resumed run writes its own.
  std::string status = "completed";
  bool final = false;
  double time = 0.0;                      // of the sample the front and tail are from
  std::int64_t step = 0;                  // of that sample
  double front = 0.0, tail = 0.0;
  /// Where the front and tail lie: x at their s, and on a terrain the bed's height z there (none on a
  /// flat grid, where s = x and the bed is no profile).
  double front_x = 0.0, tail_x = 0.0;
  std::optional<double> front_z, tail_z;
  double gate_s = 0.0;                    // s of the gate (scene gate_x, else the initial front)
  bool gate_from_scene = false;
  double from_gate = 0.0;                 // front - gate_s
  std::optional<double> runout_plane_s;   // s where the runout plane starts (none: no plane in the grid)
  std::optional<double> beyond_runout_plane;  // front - runout_plane_s
  /// Every particle had left through the open faces by this time: the front and tail above are those
  /// of the last sample that still had particles.
  std::optional<double> all_left_time;
  /// The front lies within one cell of the grid's downslope end (x+): the flow ran to the end of the
  /// grid, and the front says where the grid ends, not where the flow would stop.
  bool front_at_grid_end = false;
  // What left through the open faces by the end of the run (RunoutFiles::finish sets them): the front
  // and tail are quantiles of the mass still in the grid.
  double outflow_mass_share = 0.0;         // of the run's mass, through any open face
  double outflow_mass_share_x_plus = 0.0;  // through the x+ face: ahead of the front
  /// More mass left through x+ than the front quantile leaves ahead of the front (share_x_plus >
  /// 1 - front_quantile): the whole flow's front lay beyond the grid, and the front is not its runout.
  bool limited_by_outflow = false;
};

/// The grid along x: the runout plane's default must lie in it, and a front within one cell of its
/// end is flagged. The default is unbounded (a monitor without a grid: the tests').
struct RunoutGrid {
  double x0 = -std::numeric_limits<double>::infinity();
  double x1 = std::numeric_limits<double>::infinity();
  double h = 0.0;
};
RunoutGrid runout_grid_of(const Scene& scene);

/// x where the runout plane starts: runout_plane_x when given, else where the terrain's last straight
/// segment starts when that lies in the grid, else none (no plane: the runout is reported without one).
/// RunoutMonitor::result and `talus check`'s runout line use it.
std::optional<double> runout_plane_x(const RunoutSpec& spec, const FlumeCoordinates& coordinates, const RunoutGrid& grid);

/// Samples the run on the history schedule and keeps the first and the previous sample (the
/// reference front and the front velocity).
class RunoutMonitor {
 public:
  RunoutMonitor(const RunoutSpec& spec, FlumeCoordinates coordinates, RunoutGrid grid = {});
  const FlumeCoordinates& coordinates() const { return coordinates_; }
  /// Measure the particles at (time, step); fills front_velocity from the previous sample.
  RunoutSample sample(const ParticleStore& particles, double time, std::int64_t step);
  /// A restart: continue after these samples (the first of the run and the last before the checkpoint).
  void resume(const RunoutSample& first, const RunoutSample& last);
  bool has_samples() const { return first_.has_value(); }
  const RunoutSample& first() const { return *first_; }
  const RunoutSample& last() const { return *last_; }
  /// A sample of the particles at (time, step) that is not kept (the state where a run stopped
  /// between history rows: runout.csv, which a restart continues, does not hold it).
  RunoutSample measure(const ParticleStore& particles, double time, std::int64_t step) const;
  /// The runout after the last sample, or after `now` (a later one, from measure()); after the last
  /// one with particles, once every particle has left.
  RunoutResult result(const RunoutSample* now = nullptr) const;

 private:
  RunoutSpec spec_;
  FlumeCoordinates coordinates_;
  RunoutGrid grid_;
  std::optional<RunoutSample> first_, last_;
  std::optional<RunoutSample> last_with_particles_;
};

}  // namespace talus
