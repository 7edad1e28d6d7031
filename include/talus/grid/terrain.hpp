#pragma once
// The terrain types of the grid. The grid is uniform in (x, y, w) with w = z - z_b(x): cells keep
// vertical sides and their floors follow the terrain (Abe, Johansson & Konagai 2005, eq. 19-20 in 3D, docs/theory.md
// "Terrain-following grid"). Physical gradients need one correction,
// dN/dx_phys = dN/dx - z_b'(x) dN/dw; the map has unit Jacobian, so masses and volumes need none.
//
// The transfer kernels are templates over the terrain type, so a flat grid pays nothing:
// FlatTerrain's functions are constant and fold away. The solver picks the type once per step.
//
// ProfileTerrain is the grid's bed: the TerrainProfile sampled at the node columns x_i and
// interpolated linearly between them. Within a cell the floor is then the straight edge between two
// bed nodes, exactly the isoparametric cell of Abe, Johansson & Konagai 2005, eq. 20, so the bed nodes lie on the profile
// and linear shape functions reproduce linear fields in (x, z) exactly (docs/theory.md). The same
// map serves every shape function, the cell sort, the leave-the-grid check, seeding and restart, so
// they all agree on the cell of a particle to the last bit.
#include "talus/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace talus {

struct FlatTerrain {
  static constexpr bool kIsFlat = true;
  double height(double /*x*/) const { return 0.0; }
  double slope(double /*x*/) const { return 0.0; }
};

class TerrainProfile;

class ProfileTerrain {
 public:
  static constexpr bool kIsFlat = false;
  ProfileTerrain() = default;
  /// Samples `profile` at the node columns x_i = x0 + (i - pad) h, i = 0 .. columns - 1.
  ProfileTerrain(const TerrainProfile& profile, double x0, double h, int pad, int columns);

  /// The grid's bed height: the nodal heights interpolated linearly (Abe, Johansson & Konagai 2005, eq. 20). Beyond the
  /// sampled columns the end cells continue straight.
  double height(double x) const {
    const double xi = (x - x0_) * inv_h_ + pad_;
    const int i = cell(xi);
    const double t = xi - i;
    return z_[i] + t * (z_[i + 1] - z_[i]);
  }
  /// z_b'(x) of the grid's bed: the slope of the cell's floor (at a node column, the cell to the
  /// right, i.e. the cell the shape functions place the particle in).
  double slope(double x) const { return cell_slope_[cell((x - x0_) * inv_h_ + pad_)]; }

  /// Bed height and unit normal (up, out of the ground) of node column i. At a column where the
  /// floor bends (a kink, or a node of a circular transition) the normal is the normalised average
  /// of the normals of the two floor edges meeting there.
  double node_height(int i) const { return z_[i]; }
  const Vec3& node_normal(int i) const { return normal_[i]; }
  int columns() const { return static_cast<int>(z_.size()); }

 private:
  int cell(double xi) const {
    const int last = static_cast<int>(z_.size()) - 2;
    return std::clamp(static_cast<int>(std::floor(xi)), 0, last);
  }
  double x0_ = 0.0, inv_h_ = 1.0;
  int pad_ = 0;
  std::vector<double> z_;           // bed height per node column
  std::vector<double> cell_slope_;  // floor slope per cell (columns - 1)
  std::vector<Vec3> normal_;        // bed normal per node column
};

}  // namespace talus
