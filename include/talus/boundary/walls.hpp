#pragma once
// Axis-aligned walls on the faces of the grid domain, applied to node velocities. A node belongs to
// a face when it lies on the face or in the ghost layer beyond it.
//  fixed     v = 0
//  slip      bilateral roller: the normal component is removed (used for the sides of 1D bars)
//  friction  unilateral Coulomb contact, seed 001 eq. 14-18: only a node moving into the wall is in
//            contact (eq. 14); its normal velocity is removed (no rebound, eq. 17-18) and that
//            normal impulse |dv_n| bounds the tangential one (eq. 15-16): the node sticks when
//            |v_t| <= mu |dv_n|, otherwise slides with |v_t| reduced by mu |dv_n|. Applying the
//            rule to the step's velocity change is eq. 15-16 integrated over dt, with the cap that
//            friction never reverses the tangential motion.
//  open      nothing
#include "talus/grid/grid.hpp"
#include "talus/scene/scene.hpp"

#include <array>
#include <cmath>

namespace talus {

class Walls {
 public:
  Walls() = default;
  Walls(const std::array<std::array<WallSpec, 2>, 3>& specs, const GridGeometry& geometry);

  /// Whether any wall can touch node (i, j, k); cheap test for the common interior node.
  bool touches(const std::array<int, 3>& node) const {
    for (int d = 0; d < 3; ++d)
      if ((node[d] <= lower_[d] && active_[d][0]) || (node[d] >= upper_[d] && active_[d][1])) return true;
    return false;
  }

  /// Apply the walls of every face node (i, j, k) lies on to velocity v. `with_friction` is false
  /// for the MUSL remap, where only the no-penetration part is enforced (friction acted already).
  /// Returns the work dissipated by friction on a node of mass `m` whose velocity at the start of
  /// the step was `v_start`: -J_t . v_start,t with J_t = m dv_t the friction impulse. (The start
  /// velocity is a momentum average and stays bounded; the trial velocity of a nearly empty node
  /// does not, which would make a mean of the two meaningless.)
  /// (A rigid wall's normal impulse does no work; the energy a no-rebound impact removes shows up
  /// in the budget's gap, see docs/theory.md.)
  double apply(const std::array<int, 3>& node, double v[3], bool with_friction, double m = 0.0,
               const double* v_start = nullptr) const {
    double friction_work = 0.0;
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) {
        if (!active_[d][side]) continue;
        const bool on_face = side == 0 ? node[d] <= lower_[d] : node[d] >= upper_[d];
        if (on_face) friction_work += apply_one(d, side, v, with_friction, m, v_start);
      }
    return friction_work;
  }

 private:
  double apply_one(int axis, int side, double v[3], bool with_friction, double m, const double* v_start) const {
    const WallSpec& w = specs_[axis][side];
    const double inward = side == 0 ? 1.0 : -1.0;  // the wall's normal, pointing into the domain
    switch (w.type) {
      case WallType::Open: return 0.0;
      case WallType::Fixed: v[0] = v[1] = v[2] = 0.0; return 0.0;
      case WallType::Slip: v[axis] = 0.0; return 0.0;
      case WallType::Friction: {
        const double vn = v[axis] * inward;
        if (vn >= 0.0) return 0.0;  // separating or resting: no contact (seed 001 eq. 14)
        v[axis] = 0.0;              // no rebound (eq. 17-18)
        if (!with_friction) return 0.0;
        const int t1 = (axis + 1) % 3, t2 = (axis + 2) % 3;
        const double vt = std::sqrt(v[t1] * v[t1] + v[t2] * v[t2]);
        const double limit = w.friction_coefficient * (-vn);  // mu |dv_n|  (eq. 15-16)
        const double scale = vt <= limit ? 0.0 : 1.0 - limit / vt;  // stick, or slide slower
        double work = 0.0;
        for (int t : {t1, t2}) {
          const double after = v[t] * scale;
          if (v_start) work -= m * (after - v[t]) * v_start[t];
          v[t] = after;
        }
        return work;
      }
    }
    return 0.0;
  }

  std::array<std::array<WallSpec, 2>, 3> specs_{};
  std::array<std::array<bool, 2>, 3> active_{};
  std::array<int, 3> lower_{}, upper_{};  // node index of each face
};

}  // namespace talus
