#pragma once
// Grid: structured background grid, uniform spacing h; each node's scattered fields in one record
// (mass, momentum, force: kNodeRecord doubles), its Lagrangian velocity in another.
//
// Index space. The scene's domain [origin, origin + cells*h] is surrounded by kPad ghost cells on
// every side, so that any shape function's support stays inside the arrays. Node (i, j, k) sits at
// origin + (i - kPad, j - kPad, k - kPad) * h (k measured in the terrain-following w).
//
// Memory. Nodes are stored in tiles of 4x4x4, tile after tile, so the nodes a block of particles
// touches are contiguous. The arrays span the whole padded box but are committed lazily
// (LazyArray): only tiles next to particles are ever written, so memory scales with the occupied
// region, not the bounding box. `active_tiles` lists the tiles in use this step.
//
// Node records. The fields the scatter writes together (mass, momentum, force) sit side by side in
// one 64-byte record per node, so that a particle's P2G touches one cache line per node instead of
// seven, and the gather reads the velocity change from the same line; the Lagrangian velocity
// v^L has records of its own (4 doubles: two nodes a line). The transfers load and store records
// as vectors (transfer/transfer_kernels-inl.h); NodeField is one field's strided
// view of the records (or of a plain array, stride 1).
#include "talus/core/lazy_array.hpp"
#include "talus/core/types.hpp"
#include "talus/grid/terrain.hpp"
#include "talus/grid/terrain_profile.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace talus {

inline constexpr int kPad = 2;        // ghost cells beyond each domain face
inline constexpr int kTileEdge = 4;   // nodes per tile edge
inline constexpr int kTileNodes = kTileEdge * kTileEdge * kTileEdge;

/// Doubles per node record: mass, momentum (3), force (3) and one unused slot (64 bytes, a cache line).
inline constexpr int kNodeRecord = 8;
inline constexpr int kMassSlot = 0, kMomentumSlot = 1, kForceSlot = 4;
/// Doubles per Lagrangian-velocity record: v^L (3) and one unused slot (two nodes a cache line).
inline constexpr int kLagrangianRecord = 4;

/// One scalar node field: node n's value is base[n * stride] (stride kNodeRecord inside the node
/// records, 1 for a plain array). A view: it does not own the memory.
class NodeField {
 public:
  NodeField() = default;
  NodeField(double* base, std::size_t stride) : base_(base), stride_(stride) {}
  double& operator[](std::size_t n) const { return base_[n * stride_]; }
  double* data() const { return base_; }
  std::size_t stride() const { return stride_; }

 private:
  double* base_ = nullptr;
  std::size_t stride_ = 1;
};

/// A set of the fields a scatter writes (mass, momentum, force): what the ghost fold moves and what
/// BlockBuffers::add_sum_stage adds.
struct ScatteredFields {
  bool mass = false;
  bool momentum = false;
  bool force = false;
};

/// One node vector field as its three components.
using NodeVectors = std::array<NodeField, 3>;

struct GridGeometry {
  Vec3 origin = Vec3::Zero();            // physical corner of the domain (a node)
  double h = 1.0;                        // cell size
  std::array<int, 3> cells{1, 1, 1};     // domain cells per axis
  /// The bed z_b(x) (grid.terrain). Empty: a flat box, z = w. Otherwise origin[2] and the third
  /// axis are in w = z - z_b(x), and the z- face (w = origin[2]) follows the bed.
  TerrainSpec terrain;
  /// Periodic axes (x and y only; boundaries "periodic", docs/theory.md "Periodic boundaries"): the
  /// node at origin + cells*h is the node at origin, and a particle leaving through one face comes
  /// back through the other. The scene sets it from its walls.
  std::array<bool, 3> periodic{false, false, false};
  bool has_terrain() const { return !terrain.empty(); }
  bool has_periodic_axes() const { return periodic[0] || periodic[1] || periodic[2]; }
  /// A node index along a periodic axis mapped into the domain's nodes [kPad, kPad + cells): shape
  /// functions whose support reaches past a periodic face land on the nodes of the other side.
  /// Other axes: unchanged.
  int wrap_node(int axis, int i) const {
    if (!periodic[axis]) return i;
    const int c = cells[axis];
    const int r = (i - kPad) % c;
    return kPad + (r < 0 ? r + c : r);
  }
  /// A coordinate along a periodic axis mapped into [origin, origin + cells*h) (the wrapped
  /// position of a particle that left through a periodic face; it moves at most a cell a step, so
  /// one period is enough). Round-off that would land it on the upper face puts it on the lower one.
  double wrap_position(int axis, double x) const {
    if (!periodic[axis]) return x;
    const double lo = origin[axis], length = cells[axis] * h, hi = lo + length;
    if (x < lo) {
      x += length;
      if (x >= hi) x = lo;
    } else if (x >= hi) {
      x -= length;
      if (x < lo) x = lo;
    }
    return x;
  }
  /// The padded cell index of a coordinate (axis 2 takes w), floor(to_grid). Along a periodic axis
  /// a wrapped coordinate whose quotient rounds up to the upper face stays in the last cell.
  int cell_of(int axis, double x) const {
    const int c = static_cast<int>(std::floor(to_grid(axis, x)));
    return periodic[axis] && c >= kPad + cells[axis] ? kPad + cells[axis] - 1 : c;
  }
  std::array<int, 3> nodes() const {     // nodes per axis including ghosts
    return {cells[0] + 2 * kPad + 1, cells[1] + 2 * kPad + 1, cells[2] + 2 * kPad + 1};
  }
  /// Position in grid units (node spacing 1, ghost offset included). Axis 2 takes w, not z: with a
  /// terrain, map z to w first (Grid::w_of, or the Terrain type of the transfers).
  /// Computed as the transfers' stencils compute it (times 1/h, not divided by h): the two rounded
  /// differently within an ulp of some cell faces, so the sort could put a particle in the cell
  /// below the one its stencil starts from, and a scatter write a node past its block's range.
  double to_grid(int axis, double x) const { return (x - origin[axis]) * (1.0 / h) + kPad; }
  double node_position(int axis, int index) const { return origin[axis] + (index - kPad) * h; }
};

/// The bed of a terrain grid: the profile sampled at the node columns (terrain.hpp). Throws
/// input_error for an invalid profile; an empty ProfileTerrain for a flat grid.
ProfileTerrain grid_bed(const GridGeometry& geometry);

class Grid {
 public:
  Grid() = default;
  explicit Grid(const GridGeometry& geometry);

  const GridGeometry& geometry() const { return geometry_; }
  bool has_terrain() const { return geometry_.has_terrain(); }
  /// The terrain of the transfer templates: FlatTerrain or ProfileTerrain (the caller picks the
  /// type once, from has_terrain()).
  template <class Terrain>
  const Terrain& terrain() const {
    if constexpr (Terrain::kIsFlat) return flat_;
    else return profile_;
  }
  const ProfileTerrain& profile_terrain() const { return profile_; }
  /// w = z - z_b(x) of a physical point (z itself on a flat grid). For code outside the kernels
  /// (sort, seeding, restart); the kernels use the Terrain type.
  double w_of(double x, double z) const { return has_terrain() ? z - profile_.height(x) : z; }
  /// The physical z of a point at (x, w).
  double z_of(double x, double w) const { return has_terrain() ? w + profile_.height(x) : w; }

  // Node index = x_part(i) + y_part(j) + z_part(k): separable, so the transfer kernels compute
  // three small tables per particle instead of a full index per node.
  std::size_t x_part(int i) const {
    return static_cast<std::size_t>(i >> 2) * stride_x_ + static_cast<std::size_t>(i & 3) * 16;
  }
  std::size_t y_part(int j) const {
    return static_cast<std::size_t>(j >> 2) * stride_y_ + static_cast<std::size_t>(j & 3) * 4;
  }
  std::size_t z_part(int k) const {
    return static_cast<std::size_t>(k >> 2) * kTileNodes + static_cast<std::size_t>(k & 3);
  }
  std::size_t node(int i, int j, int k) const { return x_part(i) + y_part(j) + z_part(k); }

  std::array<int, 3> tiles() const { return tiles_; }
  std::size_t tile_count() const { return static_cast<std::size_t>(tiles_[0]) * tiles_[1] * tiles_[2]; }
  /// The first node (i, j, k) of tile `t` (its slot 0).
  std::array<int, 3> node_of(std::size_t tile) const;
  /// Node (i, j, k) of local slot `s` of the tile whose first node is `first` (with node_of, the
  /// inverse of node()): a loop over a tile's nodes finds its first node once (node_of divides the
  /// tile index) and the rest from this.
  static std::array<int, 3> node_in_tile(const std::array<int, 3>& first, int slot) {
    return {first[0] + (slot >> 4), first[1] + ((slot >> 2) & 3), first[2] + (slot & 3)};
  }

  /// Replace the set of tiles in use. Only those tiles are cleared and updated each step.
  void set_active_tiles(std::vector<std::uint32_t> tiles);
  const std::vector<std::uint32_t>& active_tiles() const { return active_tiles_; }
  /// Whether grid tile `tile` is in the active set (the ghost nodes' phase asks it of a ghost's and
  /// an image's tile, grid_update.hpp).
  bool tile_active(std::size_t tile) const { return tile_active_[tile] != 0; }
  /// Zero every field on the active tiles.
  void clear_active();
  /// Zero every field of one tile (clear_active does this for each active tile, in parallel).
  void clear_tile(std::size_t tile);
  /// Zero the momentum on the active tiles (before the MUSL remap re-scatters it).
  void clear_momentum();
  /// Bytes of node data in the active tiles (what the grid really occupies).
  std::size_t active_bytes() const;

  // Node fields, as scattered: mass, momentum m v, force f (views of the node records), and the
  // Lagrangian velocity (its own records). The grid update turns them in place into velocities
  // (12 doubles stored a node, 10 used, not 18), so after it read them through the views below, which name what each
  // field holds at that point of the step (grid_update.hpp).
  NodeField mass;
  NodeVectors momentum;
  NodeVectors force;
  NodeVectors velocity_l;
  /// Doubles stored per node: the record (with its unused slot) and the Lagrangian velocity.
  static constexpr int kFieldCount = kNodeRecord + kLagrangianRecord;

  /// The record of node n: mass, momentum and force at kMassSlot, kMomentumSlot, kForceSlot.
  double* record(std::size_t n) { return records_.data() + n * kNodeRecord; }
  const double* record(std::size_t n) const { return records_.data() + n * kNodeRecord; }
  double* records() { return records_.data(); }
  const double* records() const { return records_.data(); }
  /// v^L of node n is lagrangian_records()[n * kLagrangianRecord + d].
  const double* lagrangian_records() const { return lagrangian_.data(); }
  double* lagrangian_record(std::size_t n) { return lagrangian_.data() + n * kLagrangianRecord; }

  /// v_i: `momentum` after the grid update, add_velocities_from_momentum (the remap) or add_start_velocities.
  const NodeVectors& velocity() const { return momentum; }
  /// v_i^L - v_i, the particle velocity increment: `force` after the grid update.
  const NodeVectors& velocity_change() const { return force; }
  /// v_i^L = v_i + a_i dt after the grid update.
  const NodeVectors& lagrangian_velocity() const { return velocity_l; }
  /// USF / USAVG: the start-of-step velocities start_velocities writes (into `velocity_l`).
  const NodeVectors& start_velocity() const { return velocity_l; }

 private:
  GridGeometry geometry_;
  FlatTerrain flat_;
  ProfileTerrain profile_;
  std::array<int, 3> tiles_{0, 0, 0};
  std::size_t stride_x_ = 0, stride_y_ = 0;
  std::vector<std::uint32_t> active_tiles_;
  std::vector<std::uint8_t> tile_active_;     // per grid tile: in active_tiles_
  LazyArray records_;                         // kNodeRecord doubles per node
  LazyArray lagrangian_;                      // kLagrangianRecord doubles per node
};

}  // namespace talus
