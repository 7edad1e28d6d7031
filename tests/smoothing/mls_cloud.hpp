#pragma once
// Particle clouds for the MLS smoother's tests: a sorted store with six input and output arrays,
// jittered lattices, and polynomial fields.
#include "talus/grid/grid.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_store.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace talus::mls_test {

struct Cloud {
  GridGeometry geometry;
  Grid grid;
  CellSort sort;
  ParticleStore particles;
  std::array<std::vector<double>, 6> in, out;

  std::array<const double*, 6> inputs() const {
    std::array<const double*, 6> a;
    for (int c = 0; c < 6; ++c) a[c] = in[c].data();
    return a;
  }
  std::array<double*, 6> outputs() {
    std::array<double*, 6> a;
    for (int c = 0; c < 6; ++c) a[c] = out[c].data();
    return a;
  }
  /// Sort (the smoother needs the sort of the current positions) and size the arrays.
  void finish() {
    grid = Grid(geometry);
    sort = CellSort(grid, 0, 1);
    sort.sort(particles, grid);
    for (int c = 0; c < 6; ++c) {
      in[c].assign(particles.size(), 0.0);
      out[c].assign(particles.size(), 0.0);
    }
  }
  /// Every input component set to values drawn uniformly from [-1, 1] by a generator seeded with
  /// `seed`: an arbitrary field for comparing two evaluations of the smoother.
  void set_random_inputs(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 6; ++k)
      for (auto& v : in[k]) v = u(rng);
  }
  void set_field(const std::function<double(int, const double*)>& f) {
    for (std::size_t p = 0; p < particles.size(); ++p) {
      const double x[3] = {particles.x[0][p], particles.x[1][p], particles.x[2][p]};
      for (int c = 0; c < 6; ++c) in[c][p] = f(c, x);
    }
  }
};

/// `per_axis` particles per axis with spacing `spacing` (cell size 1), each moved by up to
/// `jitter` spacings at random, in body `body` starting at `corner`.
inline void add_lattice(Cloud& cloud, std::array<int, 3> per_axis, double spacing, double jitter, Vec3 corner,
                 std::uint16_t body, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (int i = 0; i < per_axis[0]; ++i)
    for (int j = 0; j < per_axis[1]; ++j)
      for (int k = 0; k < per_axis[2]; ++k) {
        Vec3 x = corner + spacing * Vec3(i + 0.5 + u(rng), j + 0.5 + u(rng), k + 0.5 + u(rng));
        cloud.particles.add(static_cast<std::int64_t>(cloud.particles.size()), x, Vec3::Zero(), 1.0, 1.0, body);
      }
}

/// Three jittered bodies and a lone particle that the guard stops (cell size 1, 12 x 8 x 8 cells),
/// sorted, inputs zero: the cloud the instruction-set, stored-weight and cell-fit tests use. The
/// second body starts at x = second_x: at 5.6 it touches the first, at 5.3 the two share cells.
inline Cloud three_body_cloud(double second_x = 5.6) {
  Cloud c;
  c.geometry.h = 1.0;
  c.geometry.cells = {12, 8, 8};
  add_lattice(c, {9, 8, 7}, 0.5, 0.45, Vec3(1.0, 1.3, 0.7), 0, 3);
  add_lattice(c, {5, 5, 5}, 0.5, 0.45, Vec3(second_x, 1.3, 0.7), 1, 4);
  add_lattice(c, {4, 4, 4}, 0.5, 0.45, Vec3(8.5, 4.0, 4.0), 2, 5);
  c.particles.add(9999, Vec3(10.5, 1.5, 6.5), Vec3::Zero(), 1.0, 1.0, 0);  // alone: the guard
  c.finish();
  return c;
}

/// Two jittered bodies that touch (9 x 8 x 7 and 5 x 5 x 5 particles, cell size 1), sorted, with
/// random inputs: the cloud the brute-force comparisons use.
inline Cloud two_body_cloud() {
  Cloud c;
  c.geometry.h = 1.0;
  c.geometry.cells = {10, 10, 10};
  add_lattice(c, {9, 8, 7}, 0.5, 0.45, Vec3(1.0, 1.3, 0.7), 0, 3);
  add_lattice(c, {5, 5, 5}, 0.5, 0.45, Vec3(5.6, 1.3, 0.7), 1, 4);
  c.finish();
  c.set_random_inputs(11);
  return c;
}

/// A lone particle and a pair (cell size 1, 10 x 10 x 10 cells), sorted, with the field k + x:
/// too few neighbours anywhere for the 4 terms of the linear basis.
inline Cloud sparse_cloud() {
  Cloud c;
  c.geometry.h = 1.0;
  c.geometry.cells = {10, 10, 10};
  c.particles.add(0, Vec3(2.2, 2.2, 2.2), Vec3::Zero(), 1.0, 1.0, 0);
  c.particles.add(1, Vec3(7.2, 7.2, 7.2), Vec3::Zero(), 1.0, 1.0, 0);
  c.particles.add(2, Vec3(7.6, 7.2, 7.2), Vec3::Zero(), 1.0, 1.0, 0);
  c.finish();
  c.set_field([](int k, const double* x) { return k + x[0]; });
  return c;
}

inline Cloud box_cloud(int per_axis, double jitter, unsigned seed = 1) {
  Cloud c;
  c.geometry.h = 1.0;
  c.geometry.cells = {12, 12, 12};
  add_lattice(c, {per_axis, per_axis, per_axis}, 0.5, jitter, Vec3(1.0, 1.0, 1.0), 0, seed);
  c.finish();
  return c;
}

inline double linear_field(int c, const double* x) { return 1e-3 * (1.0 + c) + 2e-4 * x[0] - 3e-4 * x[1] + (1e-4 * c) * x[2]; }
inline double quadratic_field(int c, const double* x) {
  return linear_field(c, x) + 5e-5 * x[0] * x[0] - 4e-5 * x[1] * x[2] + 3e-5 * (c + 1) * x[2] * x[2] + 1e-5 * x[0] * x[1];
}

/// The largest relative change |out - in| / |in| over every particle and component.
inline double worst_relative_change(const Cloud& c) {
  double worst = 0.0;
  for (int k = 0; k < 6; ++k)
    for (std::size_t p = 0; p < c.particles.size(); ++p)
      worst = std::max(worst, std::abs(c.out[k][p] - c.in[k][p]) / std::abs(c.in[k][p]));
  return worst;
}

}  // namespace talus::mls_test
