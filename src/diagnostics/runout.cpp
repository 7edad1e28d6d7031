#include "talus/diagnostics/runout.hpp"

#include "talus/core/parallel_sort.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace talus {

namespace {

struct Entry {
  double s;
  std::int64_t id;
  std::size_t index;
};

}  // namespace

int measure_runout_regions(std::size_t n, int threads) { return 2 + parallel_sort_regions(n, threads); }

void locate_front_and_tail(RunoutSample& r, const FlumeCoordinates& c) {
  const double none = std::numeric_limits<double>::quiet_NaN();
  // (a front of NaN, no particle left, has no x; x_at would extrapolate the terrain from it)
  r.front_x = std::isfinite(r.front) ? c.x_at(r.front) : none;
  r.tail_x = std::isfinite(r.tail) ? c.x_at(r.tail) : none;
  const bool on_terrain = !c.flat();
  r.front_z = on_terrain && std::isfinite(r.front_x) ? c.profile().height(r.front_x) : none;
  r.tail_z = on_terrain && std::isfinite(r.tail_x) ? c.profile().height(r.tail_x) : none;
}

RunoutSample measure_runout(const ParticleStore& P, const FlumeCoordinates& c, double front_quantile,
                            double tail_quantile) {
  RunoutSample r;
  const std::size_t n = P.size();
  if (n == 0) {  // nothing left to measure: no position is a number (not 0, a place on the flume)
    const double none = std::numeric_limits<double>::quiet_NaN();
    r.front = r.tail = r.s_min = r.s_max = r.centre_s = r.centre_velocity_s = none;
    r.centre = Vec3::Constant(none);
    locate_front_and_tail(r, c);
    return r;
  }
  std::vector<Entry> order(n);
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p) order[p] = Entry{c.s(P.x[0][p]), P.id[p], p};
  // (s, id) is a total order (ids are unique), so the parallel sort gives the same order for any
  // thread count, and the quantiles and sums below the same bits.
  parallel_sort(order, [](const Entry& a, const Entry& b) { return a.s < b.s || (a.s == b.s && a.id < b.id); });

  // The terms of the sums, in (s, id) order, in parallel: the gathers by index and the bed's
  // tangent are the costly part. The sums themselves then run serially over contiguous terms, in
  // (s, id) order as before, so they have the bits they had when the loop below did everything.
  struct Terms {
    double m, ms, mx[3], mv;
  };
  std::vector<Terms> terms(n);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t p = order[i].index;
    const double m = P.mass[p];
    const Vec3 t = c.tangent(P.x[0][p]);
    terms[i] = Terms{m, m * order[i].s, {m * P.x[0][p], m * P.x[1][p], m * P.x[2][p]},
                     m * (P.v[0][p] * t[0] + P.v[1][p] * t[1] + P.v[2][p] * t[2])};
  }
  double mass = 0.0;
  for (const Terms& t : terms) mass += t.m;
  r.mass = mass;
  r.s_min = order.front().s;
  r.s_max = order.back().s;
  // Quantiles: the first particle, in (s, id) order, at which the cumulative mass reaches q M.
  const double tail_mass = tail_quantile * mass, front_mass = front_quantile * mass;
  bool have_tail = false, have_front = false;
  double cumulative = 0.0, sum_s = 0.0, sum_v = 0.0;
  Vec3 sum_x = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Terms& t = terms[i];
    cumulative += t.m;
    if (!have_tail && cumulative >= tail_mass) {
      r.tail = order[i].s;
      have_tail = true;
    }
    if (!have_front && cumulative >= front_mass) {
      r.front = order[i].s;
      have_front = true;
    }
    sum_s += t.ms;
    for (int d = 0; d < 3; ++d) sum_x[d] += t.mx[d];
    sum_v += t.mv;
  }
  if (!have_front) r.front = r.s_max;  // round-off: the cumulative sum fell a hair short of q M
  if (!have_tail) r.tail = r.s_max;
  r.centre_s = sum_s / mass;
  r.centre = sum_x / mass;
  r.centre_velocity_s = sum_v / mass;
  locate_front_and_tail(r, c);
  return r;
}

DepositRaster measure_deposit(const ParticleStore& P, const FlumeCoordinates& c, double s0, double s1, double y0,
                              double y1, double cell) {
  if (!(cell > 0.0) || !(s1 > s0) || !(y1 > y0))
    throw std::invalid_argument("measure_deposit: empty raster or cell size <= 0");
  DepositRaster r;
  r.s0 = s0;
  r.y0 = y0;
  r.ds = r.dy = cell;
  r.ns = std::max(1, static_cast<int>(std::ceil((s1 - s0) / cell - 1e-9)));
  r.ny = std::max(1, static_cast<int>(std::ceil((y1 - y0) / cell - 1e-9)));
  r.thickness.assign(static_cast<std::size_t>(r.ns) * r.ny, 0.0);
  r.seeded_thickness.assign(r.thickness.size(), 0.0);
  std::vector<std::size_t> by_id(P.size());
  std::iota(by_id.begin(), by_id.end(), std::size_t{0});
  parallel_sort(by_id, [&](std::size_t a, std::size_t b) { return P.id[a] < P.id[b]; });  // ids are unique
  const double area = r.ds * r.dy;
  for (std::size_t p : by_id) {
    const double fi = std::floor((c.s(P.x[0][p]) - s0) / r.ds);
    const double fj = std::floor((P.x[1][p] - y0) / r.dy);
    if (fi < 0 || fi >= r.ns || fj < 0 || fj >= r.ny) {
      r.volume_outside += P.volume[p];
      continue;
    }
    const std::size_t cell = static_cast<std::size_t>(fi) * r.ny + static_cast<std::size_t>(fj);
    r.thickness[cell] += P.volume[p] / area;
    r.seeded_thickness[cell] += P.volume0[p] / area;
  }
  return r;
}

RunoutGrid runout_grid_of(const Scene& scene) {
  const GridGeometry& g = scene.grid;
  return RunoutGrid{g.origin[0], g.origin[0] + g.cells[0] * g.h, g.h};
}

std::optional<double> runout_plane_x(const RunoutSpec& spec, const FlumeCoordinates& coordinates, const RunoutGrid& grid) {
  if (spec.has_runout_plane) return spec.runout_plane_x;
  // The default is left out when it lies outside the grid, as a runout_plane_x there is refused (a
  // grid cut short of the terrain's last transition was "3.1 m short of the runout plane").
  if (const auto start = coordinates.last_segment_start(); start && *start >= grid.x0 && *start <= grid.x1) return start;
  return std::nullopt;
}

RunoutMonitor::RunoutMonitor(const RunoutSpec& spec, FlumeCoordinates coordinates, RunoutGrid grid)
    : spec_(spec), coordinates_(std::move(coordinates)), grid_(grid) {}

RunoutSample RunoutMonitor::measure(const ParticleStore& particles, double time, std::int64_t step) const {
  RunoutSample s = measure_runout(particles, coordinates_, spec_.front_quantile, spec_.tail_quantile);
  s.time = time;
  s.step = step;
  if (last_ && time > last_->time) s.front_velocity = (s.front - last_->front) / (time - last_->time);
  return s;
}

RunoutSample RunoutMonitor::sample(const ParticleStore& particles, double time, std::int64_t step) {
  const RunoutSample s = measure(particles, time, step);
  if (!first_) first_ = s;
  last_ = s;
  if (s.mass > 0.0) last_with_particles_ = s;
  return s;
}

void RunoutMonitor::resume(const RunoutSample& first, const RunoutSample& last) {
  first_ = first;
  last_ = last;
  if (last.mass > 0.0) last_with_particles_ = last;
}

RunoutResult RunoutMonitor::result(const RunoutSample* now) const {
  RunoutResult r;
  if (!last_) return r;
  const RunoutSample& latest = now ? *now : *last_;
  const bool all_left = !(latest.mass > 0.0) && last_with_particles_;
  const RunoutSample& measured = all_left ? *last_with_particles_ : latest;
  if (all_left) r.all_left_time = latest.time;
  r.time = measured.time;
  r.step = measured.step;
  r.front = measured.front;
  r.tail = measured.tail;
  RunoutSample located = measured;  // (located anew: a sample given to resume() may not be)
  locate_front_and_tail(located, coordinates_);
  r.front_x = located.front_x;
  r.tail_x = located.tail_x;
  if (std::isfinite(located.front_z) && std::isfinite(located.tail_z)) {  // (none on a flat grid)
    r.front_z = located.front_z;
    r.tail_z = located.tail_z;
  }
  r.gate_from_scene = spec_.has_gate;
  r.gate_s = spec_.has_gate ? coordinates_.s(spec_.gate_x) : first_->front;
  r.from_gate = r.front - r.gate_s;
  r.front_at_grid_end = coordinates_.x_at(r.front) >= grid_.x1 - grid_.h;
  if (const std::optional<double> plane_x = runout_plane_x(spec_, coordinates_, grid_)) {
    r.runout_plane_s = coordinates_.s(*plane_x);
    r.beyond_runout_plane = r.front - *r.runout_plane_s;
  }
  return r;
}

}  // namespace talus
