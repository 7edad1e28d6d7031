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
// On a terrain grid (grid.terrain) the z- face is the bed: its nodes (w = 0, and the ghosts below)
// carry the bed normal of their column (ProfileTerrain::node_normal; at a kink the normalised
// average of the two sides), and every wall type acts along that normal instead of z: friction is
// the same Coulomb rule with a general normal (seed 001 eq. 14-18 as written, with n the bed normal),
// slip removes the normal component, fixed all. The z+ face follows the terrain too (normal -n).
// The x and y faces are vertical planes on any grid (cells keep vertical sides), so they stay
// axis-aligned.
#include "talus/grid/grid.hpp"
#include "talus/scene/scene.hpp"

#include <array>
#include <cmath>
#include <vector>

namespace talus {

class Walls {
 public:
  Walls() = default;
  /// `bed`: the grid's terrain (empty on a flat grid), whose node normals the z faces use.
  Walls(const std::array<std::array<WallSpec, 2>, 3>& specs, const GridGeometry& geometry,
        const ProfileTerrain& bed = ProfileTerrain());

  /// Whether any wall can touch node (i, j, k); cheap test for the common interior node.
  bool touches(const std::array<int, 3>& node) const {
    for (int d = 0; d < 3; ++d)
      if ((node[d] <= lower_[d] && active_[d][0]) || (node[d] >= upper_[d] && active_[d][1])) return true;
    return false;
  }

  /// How a frictional (unilateral) wall treats a node's velocity.
  ///  GridUpdate  the contact decision of the step (seed 001 eq. 14-18) on the trial velocity v^L:
  ///              a node moving into the wall is in contact, loses its normal velocity, and friction
  ///              acts on its tangential velocity.
  ///  Remap       the MUSL remap v^{k+1} (the strain velocity): the node keeps the contact state the
  ///              grid update gave it. `contact_velocity` is that node's v^L: a node in contact
  ///              (v^L . n = 0) has no normal velocity in v^{k+1} either (eq. 18), whichever way the
  ///              remapped momentum points; a node that separated is free unless v^{k+1} penetrates.
  ///  Start       USF / USAVG, the start-of-step velocities used for the first strain update, before
  ///              this step's contact is known: a wall node with mass is treated as touching (normal
  ///              velocity removed); the grid update that follows decides separation.
  /// Why Remap and Start must not re-test the contact: the particles move with v^L, so a wall node
  /// held in the grid update does not move; a strain velocity in which the same node moves away from
  /// (or into) the wall stretches (or squeezes) the first cell without any motion of the material.
  /// That spurious strain energy was a +40..85% energy gain over a few impacts
  /// (inputs/benchmarks/elastic_free_fall.json, block_between_walls.json; docs/verification.md).
  enum class Stage { GridUpdate, Remap, Start };

  /// Apply the walls of every face node (i, j, k) lies on to velocity v at the given stage.
  /// GridUpdate returns the work dissipated by friction on a node of mass `m` whose velocity at the start of
  /// the step was `v_start`: -J_t . v_start,t with J_t = m dv_t the friction impulse. (The start
  /// velocity is a momentum average and stays bounded; the trial velocity of a nearly empty node
  /// does not, which would make a mean of the two meaningless.)
  /// (A rigid wall's normal impulse does no work; the energy a no-rebound impact removes shows up
  /// in the budget's gap, see docs/theory.md.)
  double apply(const std::array<int, 3>& node, double v[3], Stage stage, double m = 0.0,
               const double* v_start = nullptr, const double* contact_velocity = nullptr) const {
    double friction_work = 0.0;
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) {
        if (!active_[d][side]) continue;
        const bool on_face = side == 0 ? node[d] <= lower_[d] : node[d] >= upper_[d];
        if (on_face) friction_work += apply_one(d, side, v, stage, m, v_start, contact_velocity, node[0]);
      }
    return friction_work;
  }

 private:
  double apply_one(int axis, int side, double v[3], Stage stage, double m, const double* v_start,
                   const double* contact_velocity, int column) const {
    const WallSpec& w = specs_[axis][side];
    if (axis == 2 && !bed_normal_.empty()) {
      const Vec3& up = bed_normal_[static_cast<std::size_t>(column)];
      const double n[3] = {side == 0 ? up[0] : -up[0], side == 0 ? up[1] : -up[1], side == 0 ? up[2] : -up[2]};
      return apply_along_normal(w, n, v, stage, m, v_start, contact_velocity);
    }
    const double inward = side == 0 ? 1.0 : -1.0;  // the wall's normal, pointing into the domain
    switch (w.type) {
      case WallType::Open: return 0.0;
      case WallType::Fixed: v[0] = v[1] = v[2] = 0.0; return 0.0;
      case WallType::Slip: v[axis] = 0.0; return 0.0;
      case WallType::Friction: {
        const double vn = v[axis] * inward;
        bool contact = vn < 0.0;  // moving into the wall (seed 001 eq. 14)
        if (stage == Stage::Remap) contact = contact || contact_velocity[axis] * inward <= 0.0;
        if (stage == Stage::Start) contact = true;
        if (!contact) return 0.0;  // separating: free
        v[axis] = 0.0;             // no rebound (eq. 17-18)
        if (stage != Stage::GridUpdate || vn >= 0.0) return 0.0;  // friction acts once, in the grid update
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

  /// The same rules as apply_one for a wall of unit inward normal n (the bed of a terrain grid).
  /// The stages as in apply_one (Walls::Stage), with v.n in place of v[axis] * inward.
  static double apply_along_normal(const WallSpec& w, const double n[3], double v[3], Stage stage, double m,
                                   const double* v_start, const double* contact_velocity) {
    const double vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    switch (w.type) {
      case WallType::Open: return 0.0;
      case WallType::Fixed: v[0] = v[1] = v[2] = 0.0; return 0.0;
      case WallType::Slip:
        for (int d = 0; d < 3; ++d) v[d] -= vn * n[d];
        return 0.0;
      case WallType::Friction: {
        bool contact = vn < 0.0;  // moving into the bed (seed 001 eq. 14)
        if (stage == Stage::Remap) {
          // in contact in the grid update: v^L . n = 0 up to the round-off of removing v_n along a
          // general normal (a separating node has v^L . n of the order of its speed)
          const double* c = contact_velocity;
          const double cn = c[0] * n[0] + c[1] * n[1] + c[2] * n[2];
          contact = contact || cn <= 1e-12 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        }
        if (stage == Stage::Start) contact = true;
        if (!contact) return 0.0;                       // separating: free
        for (int d = 0; d < 3; ++d) v[d] -= vn * n[d];  // no rebound: v.n = 0 (eq. 17-18)
        if (stage != Stage::GridUpdate || vn >= 0.0) return 0.0;  // friction acts once, in the grid update
        const double vt = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);  // v is tangential now
        const double limit = w.friction_coefficient * (-vn);                   // mu |dv_n|  (eq. 15-16)
        const double scale = vt <= limit ? 0.0 : 1.0 - limit / vt;              // stick, or slide slower
        double work = 0.0;
        for (int d = 0; d < 3; ++d) {
          const double after = v[d] * scale;
          // -J_t . v_start: J_t is tangential, so only v_start's tangential part contributes
          if (v_start) work -= m * (after - v[d]) * v_start[d];
          v[d] = after;
        }
        return work;
      }
    }
    return 0.0;
  }

  std::array<std::array<WallSpec, 2>, 3> specs_{};
  std::vector<Vec3> bed_normal_;  // per node column (x index); empty on a flat grid
  std::array<std::array<bool, 2>, 3> active_{};
  std::array<int, 3> lower_{}, upper_{};  // node index of each face
};

}  // namespace talus
