#pragma once
// The nodes and weights one particle talks to: per axis, kNodes node-index parts and weights, so
// that node (a, b, c) is ix[a] + iy[b] + iz[c] and N = wx[a] wy[b] wz[c] (tensor product,
// Edo & Matsubara 2015, eq. 32). Gradients are in physical units (1/h applied); for a terrain grid the x
// derivative gains the mapping term -z_b'(x) dN/dw (docs/theory.md).
#include "talus/grid/grid.hpp"

#include <cstddef>
#include <type_traits>
#include <utility>

namespace talus {

template <class Shape>
struct Stencil {
  static constexpr int N = Shape::kNodes;
  std::size_t ix[N], iy[N], iz[N];
  double wx[N], wy[N], wz[N];
  double gx[N], gy[N], gz[N];  // d w / d x in 1/m
  double terrain_slope = 0.0;  // z_b'(x) at the particle (0 on a flat grid)
  int first[3];                // padded node indices of node (0, 0, 0), before any periodic wrap

  /// One half width (grid units) for all three axes.
  template <class Terrain>
  [[gnu::always_inline]] inline void evaluate(const Grid& grid, const Terrain& terrain, double x, double y, double z,
                                              double half_width) {
    const double hw[3] = {half_width, half_width, half_width};
    evaluate(grid, terrain, x, y, z, hw);
  }

  /// Per-axis half widths of the particle domain in grid units (GIMP; ignored by point shapes).
  /// Always inlined: it runs once per particle in each of the four transfer passes, and as a call
  /// it cost 7% of a linear elastic step (its tables then live in memory, not registers).
  template <class Terrain>
  [[gnu::always_inline]] inline void evaluate(const Grid& grid, const Terrain& terrain, double x, double y, double z,
                                              const double half_width[3]) {
    const GridGeometry& g = grid.geometry();
    const double inv_h = 1.0 / g.h;
    double w_coord = z;
    if constexpr (!Terrain::kIsFlat) {
      w_coord = z - terrain.height(x);
      terrain_slope = terrain.slope(x);
    }
    int bx, by, bz;
    Shape::weights((x - g.origin[0]) * inv_h + kPad, half_width[0], bx, wx, gx);
    Shape::weights((y - g.origin[1]) * inv_h + kPad, half_width[1], by, wy, gy);
    Shape::weights((w_coord - g.origin[2]) * inv_h + kPad, half_width[2], bz, wz, gz);
    first[0] = bx;
    first[1] = by;
    first[2] = bz;
    if (g.has_periodic_axes()) [[unlikely]] {
      // periodic boundaries: a support reaching past a periodic face lands on the wrapped nodes
      for (int a = 0; a < N; ++a) {
        ix[a] = grid.x_part(g.wrap_node(0, bx + a));
        iy[a] = grid.y_part(g.wrap_node(1, by + a));
        iz[a] = grid.z_part(bz + a);
        gx[a] *= inv_h;
        gy[a] *= inv_h;
        gz[a] *= inv_h;
      }
      return;
    }
    for (int a = 0; a < N; ++a) {
      ix[a] = grid.x_part(bx + a);
      iy[a] = grid.y_part(by + a);
      iz[a] = grid.z_part(bz + a);
      gx[a] *= inv_h;
      gy[a] *= inv_h;
      gz[a] *= inv_h;
    }
  }

  /// Shape-function gradient of node (a, b, c) in physical coordinates.
  void gradient(int a, int b, int c, double& dx, double& dy, double& dz) const {
    dx = gx[a] * wy[b] * wz[c];
    dy = wx[a] * gy[b] * wz[c];
    dz = wx[a] * wy[b] * gz[c];
    if (terrain_slope != 0.0) dx -= terrain_slope * dz;  // dN/dx_phys = dN/dx - z_b' dN/dw
  }
};

/// The shape's narrow variant (same weights on fewer nodes, for particles whose domain fits it),
/// or void where the shape has none.
template <class Shape>
struct NarrowShapeOf {
  using type = void;
};
template <class Shape>
  requires requires { typename Shape::Narrow; }
struct NarrowShapeOf<Shape> {
  using type = typename Shape::Narrow;
};

/// The stencil of one particle after another, on the fewest nodes its weights need: for a shape
/// with a Narrow variant (cpGIMP) a particle whose half widths all fit it is evaluated on the
/// narrow support, the others on the full one. The nodes dropped have weight and gradient exactly
/// zero, so every sum is the same; visit() hands the stencil to `body` as `const auto&`, and the
/// body reads its node count from the stencil's type (decltype(s)::N), keeping compile-time extents.
template <class Shape>
class ParticleStencil {
  using Narrow = typename NarrowShapeOf<Shape>::type;
  static constexpr bool kHasNarrow = !std::is_void_v<Narrow>;
  struct None {};

 public:
  template <class Terrain, class Body>
  [[gnu::always_inline]] inline void visit(const Grid& grid, const Terrain& terrain, double x, double y, double z,
                                           const double half_width[3], Body&& body) {
    if constexpr (kHasNarrow) {
      constexpr double fit = Narrow::kMaxHalfWidth;
      if (half_width[0] <= fit && half_width[1] <= fit && half_width[2] <= fit) {
        narrow_.evaluate(grid, terrain, x, y, z, half_width);
        body(std::as_const(narrow_));
        return;
      }
    }
    full_.evaluate(grid, terrain, x, y, z, half_width);
    body(std::as_const(full_));
  }

 private:
  Stencil<Shape> full_;
  [[no_unique_address]] std::conditional_t<kHasNarrow, Stencil<std::conditional_t<kHasNarrow, Narrow, Shape>>, None> narrow_;
};

}  // namespace talus
