#pragma once
// The terrain hook of the grid. The grid is uniform in (x, y, w) with w = z - z_b(x): cells keep
// vertical sides and their floors follow the terrain (seed 001 eq. 19-20 in 3D, see docs/theory.md).
// Physical gradients need one correction, dN/dx_phys = dN/dx - z_b'(x) dN/dw; the map has unit
// Jacobian, so masses and volumes need none.
//
// The transfer kernels are templates over the terrain type, so a flat grid pays nothing: FlatTerrain's
// functions are constant and fold away. The slope issue adds a piecewise terrain type.

namespace talus {

struct FlatTerrain {
  static constexpr bool kIsFlat = true;
  double height(double /*x*/) const { return 0.0; }
  double slope(double /*x*/) const { return 0.0; }
};

}  // namespace talus
