#pragma once
// Axis-aligned walls on the faces of the grid domain, applied to node velocities. A node belongs to
// a face when it lies on the face or in the ghost layer beyond it.
//  fixed     v = 0
//  slip      bilateral roller: the normal component is removed (used for the sides of 1D bars)
//  friction  unilateral Coulomb contact, Abe, Johansson & Konagai 2005, eq. 14-18: only a node moving into the wall is in
//            contact (eq. 14); its normal velocity is removed (no rebound, eq. 17-18) and that
//            normal impulse |dv_n| bounds the tangential one (eq. 15-16): the node sticks when
//            |v_t| <= mu |dv_n|, otherwise slides with |v_t| reduced by mu |dv_n|. Applying the
//            rule to the step's velocity change is eq. 15-16 integrated over dt, with the cap that
//            friction never reverses the tangential motion.
//  open      nothing
//  periodic  nothing: the face is no wall, the grid wraps its nodes and particles onto the opposite
//            face (GridGeometry::periodic); inactive here and never mirrored
// On a terrain grid (grid.terrain) the z- face is the bed: its nodes (w = 0, and the ghosts below)
// carry the bed normal of their column (ProfileTerrain::node_normal; at a kink the normalised
// average of the two sides), and every wall type acts along that normal instead of z: friction is
// the same Coulomb rule with a general normal (Abe, Johansson & Konagai 2005, eq. 14-18 as written, with n the bed normal),
// slip removes the normal component, fixed all. The z+ face follows the terrain too (normal -n).
// The x and y faces are vertical planes on any grid (cells keep vertical sides), so they stay
// axis-aligned.
#include "talus/boundary/wall_spec.hpp"
#include "talus/grid/grid.hpp"

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

  /// Mirrored ghost nodes (fixed and slip walls). The supports of the B-spline and of wide GIMP
  /// domains next to a wall reach the ghost nodes beyond it. Holding those like the wall node makes
  /// the velocity field flat across the first cell, which over-stiffens it (the B-spline column's
  /// first particles read +8% and +29% stress). Instead a ghost node takes the reflection of the
  /// interior node at the same distance from the wall: odd for the velocity components the wall
  /// holds (all at a fixed wall, the normal one at a slip wall), even for the free ones, so the
  /// interpolated field satisfies the wall condition at the wall with an undisturbed gradient.
  /// `mirror(node, mirrored, sign)`: false when the node is no such ghost; else the interior node
  /// and the factor per velocity component. Frictional (unilateral) walls are not mirrored.
  /// The ghost is a slave of its image (u_ghost = sign u_image), so in the Galerkin sense its mass,
  /// momentum and force belong to the image: the grid's node phases add them there (sign-weighted,
  /// fold_tile in grid_update.cpp) before the image's velocity is computed, and copy the result back
  /// (add_node_phase; the ghosts are listed once by GhostMap).
  bool mirror(const std::array<int, 3>& node, std::array<int, 3>& mirrored, std::array<double, 3>& sign) const {
    bool ghost = false;
    mirrored = node;
    sign = {1.0, 1.0, 1.0};
    for (int d = 0; d < 3; ++d) {
      for (int side = 0; side < 2; ++side) {
        if (!mirrored_face(d, side)) continue;
        const WallType type = specs_[d][side].type;
        const int face = side == 0 ? lower_[d] : upper_[d];
        const bool beyond = side == 0 ? node[d] < face : node[d] > face;
        if (!beyond) continue;
        const int image = 2 * face - node[d];
        if (image < lower_[d] || image > upper_[d]) return false;  // deeper than the domain is wide
        mirrored[d] = image;
        if (type == WallType::Fixed) for (double& f : sign) f = -f;
        else sign[d] = -sign[d];
        ghost = true;
      }
    }
    return ghost;
  }
  /// Ghosts one image can have: a node within reach of both faces along each axis (a domain
  /// narrower than 2 kPad cells) has up to 3 choices per axis, 3^3 - 1 combinations.
  static constexpr int kMaxGhosts = 26;
  using GhostNodes = std::array<std::array<int, 3>, kMaxGhosts>;
  using GhostSigns = std::array<std::array<double, 3>, kMaxGhosts>;
  /// The inverse of mirror(): the ghost nodes whose image is `node` (one per combination of the
  /// mirrored faces within reach along the axes: 7 at a box's corner, more in a domain narrower
  /// than 2 kPad cells), with their factors. Returns the count written to `ghosts` / `signs`.
  int ghosts_of(const std::array<int, 3>& node, GhostNodes& ghosts, GhostSigns& signs) const {
    // per axis: the ghost coordinate across each mirrored face (or none) and its factors
    int options[3] = {0, 0, 0};
    int coordinate[3][2];
    std::array<double, 3> factor[3][2];
    for (int d = 0; d < 3; ++d) {
      // a ghost itself: beyond a mirrored face. A node beyond a face that is not mirrored (under a
      // frictional floor, past an open face) is a node like any other, which the B-spline's support
      // reaches: a mirrored wall's ghost of it is folded into it like any ghost (mirror() pairs them).
      if ((node[d] < lower_[d] && mirrored_face(d, 0)) || (node[d] > upper_[d] && mirrored_face(d, 1))) return 0;
      for (int side = 0; side < 2; ++side) {
        if (!mirrored_face(d, side)) continue;
        const WallType type = specs_[d][side].type;
        const int face = side == 0 ? lower_[d] : upper_[d];
        const int ghost = 2 * face - node[d];
        const bool beyond = side == 0 ? ghost < face : ghost > face;
        if (!beyond || ghost < lower_[d] - kPad || ghost > upper_[d] + kPad) continue;
        coordinate[d][options[d]] = ghost;
        factor[d][options[d]] = {1.0, 1.0, 1.0};
        if (type == WallType::Fixed) factor[d][options[d]] = {-1.0, -1.0, -1.0};
        else factor[d][options[d]][d] = -1.0;
        ++options[d];
      }
    }
    int count = 0;
    // choice per axis: 0 = not mirrored, 1.. = across that option
    for (int cx = 0; cx <= options[0]; ++cx)
      for (int cy = 0; cy <= options[1]; ++cy)
        for (int cz = 0; cz <= options[2]; ++cz) {
          if (cx == 0 && cy == 0 && cz == 0) continue;
          const int choice[3] = {cx, cy, cz};
          std::array<int, 3> g = node;
          std::array<double, 3> f = {1.0, 1.0, 1.0};
          for (int d = 0; d < 3; ++d) {
            if (choice[d] == 0) continue;
            g[d] = coordinate[d][choice[d] - 1];
            for (int c = 0; c < 3; ++c) f[c] *= factor[d][choice[d] - 1][c];
          }
          std::array<int, 3> image;
          std::array<double, 3> unused;
          if (count < kMaxGhosts && mirror(g, image, unused) && image == node) {
            ghosts[count] = g;
            signs[count] = f;
            ++count;
          }
        }
    return count;
  }

  /// Whether the cube of `edge` nodes starting at `first` comes within kPad nodes of a mirrored
  /// face (so it may hold a ghost node or the image of one).
  bool near_mirrored_face(const std::array<int, 3>& first, int edge) const {
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) {
        if (!mirrored_face(d, side)) continue;
        const int face = side == 0 ? lower_[d] : upper_[d];
        if (first[d] <= face + kPad && first[d] + edge - 1 >= face - kPad) return true;
      }
    return false;
  }

  bool has_mirrored_walls() const {
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side)
        if (mirrored_face(d, side)) return true;
    return false;
  }
  /// Fixed walls and slip walls are mirrored, except a slip bed on a terrain grid: its normal is
  /// the bed normal, not the w axis the mirror reflects along (such a bed is held like the wall).
  bool mirrored_face(int axis, int side) const { return mirrors(specs_[axis][side].type, axis, !bed_normal_.empty()); }
  /// The same rule for a face of `type` on `axis`, on a terrain grid or not (for estimates made
  /// before the walls exist).
  static bool mirrors(WallType type, int axis, bool terrain_bed) {
    return type == WallType::Fixed || (type == WallType::Slip && !(axis == 2 && terrain_bed));
  }

  /// How a frictional (unilateral) wall treats a node's velocity.
  ///  GridUpdate  the contact decision of the step (Abe, Johansson & Konagai 2005, eq. 14-18) on the trial velocity v^L:
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
  /// does not, which would make a mean of the two meaningless.) Where the node sticks, J_t is a static
  /// reaction and v_start no slip, so the term is O(dt) and of either sign there: -0.39 J in a
  /// sloshing block whose bed sticks. Under FLIP it is also, to first order, the energy the impulse
  /// gives the particles (sum_p m_p v_p . N dv = m dv . v_start): a negative value is energy fed into
  /// the motion (docs/theory.md, "Negative friction work where the bed sticks").
  /// (A rigid wall's normal impulse does no work; the energy a no-rebound impact removes shows up
  /// in the budget's gap, see docs/theory.md.)
  double apply(const std::array<int, 3>& node, double v[3], Stage stage, double m = 0.0,
               const double* v_start = nullptr, const double* contact_velocity = nullptr) const {
    const double v_in[3] = {v[0], v[1], v[2]};
    double friction_work = 0.0;
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) {
        if (!active_[d][side]) continue;
        if (on_face(node, d, side)) friction_work += apply_one(d, side, v, stage, m, v_start, contact_velocity, node[0]);
      }
    if (!bed_normal_.empty() && active_[2][0] && on_face(node, 2, 0))
      for (int side = 0; side < 2; ++side)
        if (active_[0][side] && on_face(node, 0, side)) {
          Vec3 line;
          const CornerHold hold = hold_bed_corner(side, v, node, line);
          if (hold == CornerHold::None) continue;
          // The friction the walls booked acted on a velocity the corner then replaced. What the node
          // lost along the corner line, the one direction both faces leave free, is the friction's
          // impulse (the rest are the faces' normal reactions, which do no work); none where a y wall
          // then stopped the node (its normal reaction). Booked in the grid update only, as friction is.
          friction_work = 0.0;
          if (hold == CornerHold::AlongLine && stage == Stage::GridUpdate && v_start) {
            const double lost = (v[0] - v_in[0]) * line[0] + (v[1] - v_in[1]) * line[1] + (v[2] - v_in[2]) * line[2];
            const double start = v_start[0] * line[0] + v_start[1] * line[1] + v_start[2] * line[2];
            friction_work = -m * lost * start;
          }
        }
    return friction_work;
  }

 private:
  /// Whether node lies on (or beyond) face (axis, side): the nodes a wall there acts on.
  bool on_face(const std::array<int, 3>& node, int axis, int side) const {
    return side == 0 ? node[axis] <= lower_[axis] : node[axis] >= upper_[axis];
  }

  /// A node on the bed of a terrain grid and on an x face. The bed's normal leans along x, so
  /// removing the bed's normal velocity after the x wall's puts an x velocity back, -(v.n) n_x, that
  /// can point into the x wall: an elastic block at rest against a slip x wall at the foot of a 30-degree
  /// bed crept into it, its compression growing without bound (-4e5 Pa after 2 s against -3e3 Pa with
  /// rotated gravity on a flat grid). Where the x wall's rule no longer holds after the bed's (slip:
  /// any normal velocity; friction: into the wall), the node keeps only its velocity along the corner
  /// line, which both faces allow; then the y walls hold it as before (the bed's normal has no y part,
  /// so they are not disturbed otherwise). The normal impulses this takes do no work.
  enum class CornerHold { None, AlongLine, Stopped };
  CornerHold hold_bed_corner(int side, double v[3], const std::array<int, 3>& node, Vec3& line) const {
    const WallType type = specs_[0][side].type;
    if (type != WallType::Slip && type != WallType::Friction) return CornerHold::None;  // fixed: v = 0 already
    const double into = side == 0 ? -v[0] : v[0];  // > 0: into the x wall
    if (type == WallType::Slip ? into == 0.0 : into <= 0.0) return CornerHold::None;
    const Vec3& n = bed_normal_[static_cast<std::size_t>(node[0])];
    line = Vec3(0.0, -n[2], n[1]).normalized();  // e_x x n: along both faces
    const double along = v[0] * line[0] + v[1] * line[1] + v[2] * line[2];
    for (int d = 0; d < 3; ++d) v[d] = along * line[d];
    for (int y_side = 0; y_side < 2; ++y_side) {
      if (!active_[1][y_side] || !on_face(node, 1, y_side)) continue;
      const WallType y_type = specs_[1][y_side].type;
      const double y_into = y_side == 0 ? -v[1] : v[1];
      if (y_type == WallType::Fixed || y_type == WallType::Slip || (y_type == WallType::Friction && y_into > 0.0)) {
        v[0] = v[1] = v[2] = 0.0;  // the corner line runs into the y wall: nothing is left
        return CornerHold::Stopped;
      }
    }
    return CornerHold::AlongLine;
  }

  double apply_one(int axis, int side, double v[3], Stage stage, double m, const double* v_start,
                   const double* contact_velocity, int column) const {
    const WallSpec& w = specs_[axis][side];
    if (axis == 2 && !bed_normal_.empty()) {
      const Vec3& up = bed_normal_[static_cast<std::size_t>(column)];
      const double n[3] = {side == 0 ? up[0] : -up[0], side == 0 ? up[1] : -up[1], side == 0 ? up[2] : -up[2]};
      return apply_along_normal(w, n, v, stage, m, v_start, contact_velocity, kBedRemapTolerance);
    }
    // An axis wall is a wall whose inward normal is the axis (exact: the products with 0 and +-1
    // below change no bit), so both kinds share one contact rule. Its contact state in the remap
    // needs no tolerance: removing the normal velocity along an axis leaves exactly 0.
    const double inward = side == 0 ? 1.0 : -1.0;
    double n[3] = {0.0, 0.0, 0.0};
    n[axis] = inward;
    return apply_along_normal(w, n, v, stage, m, v_start, contact_velocity, 0.0);
  }

  /// The wall rules for a wall of unit inward normal n (an axis, or the bed of a terrain grid), at
  /// the stages of Walls::Stage. `remap_tolerance`: a node of the grid update's contact keeps it in
  /// the remap when its v^L . n <= remap_tolerance |v^L| (the round-off of removing v_n along a
  /// general normal; 0 along an axis).
  static double apply_along_normal(const WallSpec& w, const double n[3], double v[3], Stage stage, double m,
                                   const double* v_start, const double* contact_velocity, double remap_tolerance) {
    const double vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    switch (w.type) {
      case WallType::Open:
      case WallType::Periodic: return 0.0;
      case WallType::Fixed: v[0] = v[1] = v[2] = 0.0; return 0.0;
      case WallType::Slip:
        for (int d = 0; d < 3; ++d) v[d] -= vn * n[d];
        return 0.0;
      case WallType::Friction: {
        bool contact = vn < 0.0;  // moving into the bed (Abe, Johansson & Konagai 2005, eq. 14)
        if (stage == Stage::Remap) {
          // in contact in the grid update: v^L . n = 0 up to round-off (a separating node has
          // v^L . n of the order of its speed)
          const double* c = contact_velocity;
          const double cn = c[0] * n[0] + c[1] * n[1] + c[2] * n[2];
          contact = contact || cn <= remap_tolerance * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
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

  static constexpr double kBedRemapTolerance = 1e-12;

  std::array<std::array<WallSpec, 2>, 3> specs_{};
  std::vector<Vec3> bed_normal_;  // per node column (x index); empty on a flat grid
  std::array<std::array<bool, 2>, 3> active_{};
  std::array<int, 3> lower_{}, upper_{};  // node index of each face
};

}  // namespace talus
