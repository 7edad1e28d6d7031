#include "talus/solver/memory_estimate.hpp"

#include "talus/boundary/ghost_map.hpp"
#include "talus/core/error.hpp"
#include "talus/grid/grid.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_scratch.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/transfer/block_buffers.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace talus {

namespace {

// Per-particle arrays, in bytes (particles/particle_store.hpp, particles/particle_scratch.hpp, solver.hpp).
constexpr std::size_t kAlwaysFields = 8 /* id */ + 2 /* body */ + 8 * (3 + 3 + 1 + 1 + 1 + 6 + 6);
constexpr std::size_t kPlasticStrain = 8;
constexpr std::size_t kBackStress = 6 * 8;
constexpr std::size_t kGimpDomain = 3 * 8;
// The scratch the phases borrow in turn (particles/particle_scratch.hpp): the sort's keys and
// orders with the permutation's buffer, then the step's displacement.
constexpr std::size_t kParticleScratch = ParticleScratch::kPlanes * 4;
constexpr std::size_t kSmoothing = (6 + 6 + 3) * 8;       // raw and smoothed strain, raw spin
constexpr std::size_t kSortCell = 3 * 4;                  // the sort state a snapshot keeps
// The largest transient buffer: a particle frame's VTK arrays (points, velocity, speed, stress,
// strain, density, volume, id, body, vertex offsets and connectivity; io/vtu_writer.cpp). One
// frame at a time, held while the steps after it run (it is written in the background).
constexpr std::size_t kFrameArrays = 24 + 24 + 8 + 48 + 48 + 8 + 8 + 8 + 2 + 4 + 4;
constexpr std::size_t kNodeBytes = Grid::kFieldCount * sizeof(double);

/// The `reused` MLS variant's weights (smoothing/mls_stored_weights.hpp): 12 B per neighbour, 16 B
/// per particle, and a row of 64 B per particle for applying them. The neighbours: the particles
/// of the densest body in the ball of the radius, the ball cut to the grid along a thin axis (a
/// ball in a box of its extents fills pi/6 of it).
std::size_t reused_weight_bytes(const Scene& scene) {
  double per_cell = 0.0;
  for (const BodySpec& body : scene.bodies) per_cell = std::max(per_cell, std::pow(double(body.particles_per_cell), 3.0));
  const double r = scene.smoothing.mls.radius_factor;
  double box = 1.0;
  for (int d = 0; d < 3; ++d) box *= std::min(2.0 * r, double(scene.grid.cells[d]));
  const double neighbours = M_PI / 6.0 * box * per_cell;
  return static_cast<std::size_t>(12.0 * neighbours) + 16 + 64;
}

/// The particle store's fields (what a checkpoint and the last good state keep of each particle).
std::size_t field_bytes(const Scene& scene) {
  bool plastic = false, kinematic = false;
  for (const BodySpec& body : scene.bodies) {
    const MaterialSpec& m = scene.materials[body.material];
    if (m.model == MaterialModel::LinearElastic) continue;
    plastic = true;  // Drucker-Prager and μ(I) keep the plastic state (BodyMaterials)
    if (m.model != MaterialModel::DruckerPrager) continue;
    kinematic = kinematic || (m.drucker_prager.hardening_modulus > 0.0 && m.drucker_prager.kinematic_fraction > 0.0);
  }
  std::size_t fields = kAlwaysFields;
  if (plastic) fields += kPlasticStrain;
  if (kinematic) fields += kBackStress;
  if (scene.shape == ShapeKind::CpGimp) fields += kGimpDomain;
  return fields;
}

bool reuses_mls_weights(const Scene& scene) {
  return scene.smoothing.enabled && scene.smoothing.mls.variant == MlsVariant::Reused;
}

std::size_t bytes_per_particle(const Scene& scene, MemoryScope scope) {
  const std::size_t fields = field_bytes(scene);
  std::size_t bytes = fields + kParticleScratch;
  if (scene.smoothing.enabled) bytes += kSmoothing;
  if (reuses_mls_weights(scene)) bytes += reused_weight_bytes(scene);
  if (scope == MemoryScope::Solver) return bytes;
  bytes += kFrameArrays;
  if (scene.guards.snapshot_interval > 0) bytes += fields + kSortCell;  // the last good state
  return bytes;
}

/// Tiles of 4^3 nodes that a node range [lo, hi] of each axis meets, clipped to the grid.
std::size_t tiles_in(const std::array<int, 3>& lo, const std::array<int, 3>& hi, const std::array<int, 3>& nodes) {
  std::size_t tiles = 1;
  for (int d = 0; d < 3; ++d) {
    const int a = std::clamp(lo[d], 0, nodes[d] - 1) / kTileEdge;
    const int b = std::clamp(hi[d], 0, nodes[d] - 1) / kTileEdge;
    tiles *= static_cast<std::size_t>(b - a + 1);
  }
  return tiles;
}

/// The node data of the tiles each body's box (in the grid's x, y, w) covers, widened by the
/// largest shape function's reach (2 nodes), and with solver.scatter = "block_buffers" the node
/// boxes of the blocks those boxes meet (BlockBuffers). Overlapping bodies count twice: an upper estimate.
std::size_t start_grid_bytes(const Scene& scene) {
  const GridGeometry& g = scene.grid;
  const auto [reach_low, reach_high] = shape_reach(scene.shape);
  const int block = colour_block_edge(scene);
  const int box_edge = block + 2 * ((block - reach_low - reach_high) / 2) + reach_low + reach_high;
  std::size_t box_bytes = 0;
  const ProfileTerrain bed = grid_bed(g);
  const std::array<int, 3> nodes = g.nodes();
  std::size_t tiles = 0;
  for (const BodySpec& body : scene.bodies) {
    double w_lo = body.box_min[2], w_hi = body.box_max[2];
    if (g.has_terrain() && body.frame == BoxFrame::Physical) {
      // the bed under the box, sampled at the node columns it spans
      double bed_lo = INFINITY, bed_hi = -INFINITY;
      const int i0 = static_cast<int>(std::floor(g.to_grid(0, body.box_min[0]))) - 1;
      const int i1 = static_cast<int>(std::ceil(g.to_grid(0, body.box_max[0]))) + 1;
      for (int i = std::max(i0, 0); i <= std::min(i1, nodes[0] - 1); ++i) {
        const double zb = bed.height(g.node_position(0, i));
        bed_lo = std::min(bed_lo, zb);
        bed_hi = std::max(bed_hi, zb);
      }
      if (bed_lo <= bed_hi) {
        w_lo = std::max(g.origin[2], body.box_min[2] - bed_hi);
        w_hi = body.box_max[2] - bed_lo;
      }
    }
    const double lo[3] = {body.box_min[0], body.box_min[1], w_lo};
    const double hi[3] = {body.box_max[0], body.box_max[1], w_hi};
    std::array<int, 3> a{}, b{};
    for (int d = 0; d < 3; ++d) {
      a[d] = static_cast<int>(std::floor(std::max(g.to_grid(d, lo[d]), -1.0))) - 2;
      b[d] = static_cast<int>(std::ceil(std::min(g.to_grid(d, hi[d]), double(nodes[d])))) + 2;
    }
    tiles += tiles_in(a, b, nodes);
    if (scene.scatter == ScatterOrder::BlockBuffers) {
      std::size_t blocks = 1;
      for (int d = 0; d < 3; ++d) blocks *= static_cast<std::size_t>(std::max(b[d] - a[d], 0) / block + 2);
      box_bytes += BlockBuffers::bytes_for(blocks, box_edge);
    }
  }
  return tiles * kTileNodes * kNodeBytes + box_bytes;
}

std::optional<std::size_t> parse_size(std::string text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  if (text.empty()) return std::nullopt;
  double scale = 1.0;
  switch (std::toupper(static_cast<unsigned char>(text.back()))) {
    case 'K': scale = 1e3; break;
    case 'M': scale = 1e6; break;
    case 'G': scale = 1e9; break;
    case 'T': scale = 1e12; break;
    default: break;
  }
  if (scale != 1.0) text.pop_back();
  // decimal only: strtod also reads hexadecimal ("0x10" was 16 bytes), "inf" and "nan"
  if (text.empty() || text.find_first_not_of("0123456789.eE+-") != std::string::npos) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(value)) return std::nullopt;
  // At least a byte, and at most 2^63 (1e30 cast to an integer was undefined and read as 0 bytes).
  const double bytes = value * scale;
  if (!(bytes >= 1.0) || !(bytes <= 9.2e18)) return std::nullopt;
  return static_cast<std::size_t>(bytes);
}

/// A number from a one-line file (cgroup v2), nullopt for "max" or an unreadable file.
std::optional<std::size_t> read_number(const char* path) {
  std::ifstream in(path);
  std::string word;
  if (!(in >> word) || word == "max") return std::nullopt;
  try {
    return static_cast<std::size_t>(std::stoull(word));
  } catch (...) {
    return std::nullopt;
  }
}

/// The ghost map (boundary/ghost_map.hpp) with every tile listed: 12 B per tile of the grid, and a
/// fold and a mirror per ghost node, kPad layers beyond each mirrored face (Walls::mirrors), counted
/// over the whole face. Tiles are listed as the flow reaches them, so at
/// the start the map holds its per-tile entries and little else.
struct GhostMapBytes {
  std::size_t start = 0, bound = 0;
};
GhostMapBytes ghost_map_bytes(const Scene& scene, std::size_t all_tiles) {
  const std::array<int, 3> nodes = scene.grid.nodes();
  std::size_t ghost_nodes = 0;
  bool mirrored_walls = false;
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      if (!Walls::mirrors(scene.walls[d][side].type, d, scene.grid.has_terrain())) continue;
      mirrored_walls = true;
      ghost_nodes += static_cast<std::size_t>(kPad) * nodes[(d + 1) % 3] * static_cast<std::size_t>(nodes[(d + 2) % 3]);
    }
  if (!mirrored_walls) return {};
  const std::size_t entries = all_tiles * GhostMap::kBytesPerTile;
  return {entries, entries + 2 * ghost_nodes * sizeof(GhostMap::Pair)};
}

}  // namespace

std::size_t checkpoint_bytes_per_particle(const Scene& scene) {
  // the fields and their sort cells, and the `reused` MLS variant's weights without its rows
  return field_bytes(scene) + kSortCell + (reuses_mls_weights(scene) ? reused_weight_bytes(scene) - 64 : 0);
}

MemoryEstimate estimate_memory(const Scene& scene, MemoryScope scope) {
  MemoryEstimate e;
  e.particles = count_particles(scene);
  e.bytes_per_particle = bytes_per_particle(scene, scope);
  e.particle_bytes = e.particles * e.bytes_per_particle;
  e.grid_bytes = start_grid_bytes(scene);
  const std::array<int, 3> nodes = scene.grid.nodes();
  std::size_t all_tiles = 1;
  for (int d = 0; d < 3; ++d) all_tiles *= static_cast<std::size_t>((nodes[d] + kTileEdge - 1) / kTileEdge);
  e.grid_bytes_bound = all_tiles * kTileNodes * kNodeBytes;
  e.grid_bytes = std::min(e.grid_bytes, e.grid_bytes_bound);
  const GhostMapBytes ghosts = ghost_map_bytes(scene, all_tiles);
  e.grid_bytes += ghosts.start;
  e.grid_bytes_bound += ghosts.bound;
  // The bookkeeping over the whole grid, held from the start: a flag a tile in the grid and in the
  // sort, and the sort's index of each colour block (a 100 000 x 100 x 100 grid of 64 k particles
  // held 388 MB against 259 MB estimated without them).
  const std::size_t block = static_cast<std::size_t>(colour_block_edge(scene));
  std::size_t all_blocks = 1;
  for (int d = 0; d < 3; ++d) all_blocks *= (static_cast<std::size_t>(nodes[d]) + block - 1) / block;
  const std::size_t bookkeeping = 2 * all_tiles + sizeof(std::uint32_t) * all_blocks;
  e.grid_bytes += bookkeeping;
  e.grid_bytes_bound += bookkeeping;
  return e;
}

std::optional<std::size_t> available_memory() {
  if (const char* limit = std::getenv("TALUS_MEMORY_LIMIT")) {
    const std::optional<std::size_t> bytes = parse_size(limit);
    if (!bytes)
      throw input_error(fmt::format("TALUS_MEMORY_LIMIT = \"{}\" is not a memory size (1 byte to 9.2e18 bytes, "
                                    "optionally with K, M, G or T: 8G)", limit));
    return bytes;
  }
  std::optional<std::size_t> available;
  std::ifstream meminfo("/proc/meminfo");
  std::string line;
  while (std::getline(meminfo, line))
    if (line.rfind("MemAvailable:", 0) == 0) {
      std::istringstream fields(line.substr(13));
      std::size_t kib = 0;
      if (fields >> kib) available = kib * 1024;
    }
  const std::optional<std::size_t> cap = read_number("/sys/fs/cgroup/memory.max");
  const std::optional<std::size_t> used = read_number("/sys/fs/cgroup/memory.current");
  if (cap && used) {
    const std::size_t room = *cap > *used ? *cap - *used : 0;
    available = available ? std::min(*available, room) : room;
  }
  return available;
}

std::size_t bytes_on_this_machine(const Scene& scene, const MemoryEstimate& e, const MachineShare& share) {
  if (share.ranks <= 1) return e.total();
  const double here = double(e.total()) * double(share.ranks_here) / double(share.ranks);
  const double whole_fields = double(e.particles) * double(checkpoint_bytes_per_particle(scene));
  const double gathered = share.root_here ? whole_fields : 0.0;
  const double read_per_rank = share.restart_reads_own_part ? whole_fields / double(share.ranks) : whole_fields;
  const double restored = share.restart ? 2.0 * read_per_rank * double(share.ranks_here) : 0.0;
  return static_cast<std::size_t>(here + gathered + restored);
}

void require_memory_fits(const Scene& scene, const MemoryEstimate& e, const MachineShare& share) {
  const std::optional<std::size_t> available = available_memory();
  const std::size_t needed = bytes_on_this_machine(scene, e, share);
  if (!available || needed <= *available) return;
  // What to change: the particles and the grid both go with (1/h)^3, so a cell this many times
  // larger brings the whole down to what fits (rounded up, so that it does fit). Fewer particles per
  // cell help only when the grid alone fits.
  const double h_factor = std::ceil(100.0 * std::cbrt(double(needed) / double(std::max<std::size_t>(*available, 1)))) / 100.0;
  const bool grid_fits = e.grid_bytes < *available;
  const std::string where =
      share.ranks <= 1 ? std::string()
                       : fmt::format(" on this machine, which runs {} of the {} ranks{}{}", share.ranks_here, share.ranks,
                                     share.root_here ? " (rank 0 among them, which gathers every particle)" : "",
                                     share.restart && !share.restart_reads_own_part
                                         ? ", each of which reads the whole checkpoint (saved by another number of ranks)"
                                         : "");
  throw input_error(fmt::format(
      "scene \"{}\" needs about {}{} ({} particles x {} B + {} of grid{}) but {} is available{}; make "
      "grid.cell_size {:.2f}x larger{}, or run it on {}",
      scene.name, format_bytes(double(needed)), where, e.particles, e.bytes_per_particle, format_bytes(double(e.grid_bytes)),
      share.ranks <= 1 ? "" : " in all",
      format_bytes(double(*available)), std::getenv("TALUS_MEMORY_LIMIT") ? " (TALUS_MEMORY_LIMIT)" : "",
      std::max(h_factor, 1.01), grid_fits ? " or use fewer particles_per_cell" : " (the grid alone does not fit)",
      share.ranks <= 1 ? "a machine with more memory" : "more machines or machines with more memory"));
}

std::optional<std::string> memory_bound_warning(const MemoryEstimate& e, const MachineShare& share) {
  if (share.ranks > 1 || e.grid_bytes_bound <= e.grid_bytes) return std::nullopt;
  const std::optional<std::size_t> available = available_memory();
  const std::size_t bound = e.particle_bytes + e.grid_bytes_bound;
  if (!available || bound <= *available || e.total() > *available) return std::nullopt;
  return fmt::format(
      "memory: about {} at the start, but up to {} if the flow covers the whole grid, more than the {} available{}: a "
      "flow that spreads over the grid may run out of memory; a smaller grid or a larger grid.cell_size keeps it within",
      format_bytes(double(e.total())), format_bytes(double(bound)), format_bytes(double(*available)),
      std::getenv("TALUS_MEMORY_LIMIT") ? " (TALUS_MEMORY_LIMIT)" : "");
}

std::string format_bytes(double bytes) {
  if (bytes >= 1e12) return fmt::format("{:.2f} TB", bytes / 1e12);
  if (bytes >= 1e9) return fmt::format("{:.2f} GB", bytes / 1e9);
  if (bytes >= 1e6) return fmt::format("{:.1f} MB", bytes / 1e6);
  return fmt::format("{:.1f} kB", bytes / 1e3);
}

}  // namespace talus
