#pragma once
// The node work of a grid phase in one parallel region (issue 19, docs/performance.md "Scaling").
//
// Between two scatters a step runs several loops over the active tiles: the sum of the block
// buffers, the ghost fold, the grid update, the ghost mirror (or, after the remap's scatter, its
// sum, fold, velocities and mirror). Each used to be a parallel region of its own: a fork/join per
// loop, which costs more than the loop itself on a small scene at 16 threads. TileStages runs them
// as `omp for` loops of one parallel region:
//   - a stage that reads and writes only tile t's nodes (OwnTile: the box sum; the grid update and
//     the remap's velocities where no wall is mirrored) runs on tile t right after the stage before
//     it, in the same loop, when that loop holds only OwnTile stages: the static schedule gives tile
//     t to one thread, which finishes the earlier stages there first;
//   - a stage that reads or writes other tiles' nodes (AnyTile: a node phase with the ghosts' fold
//     and mirror, solver/grid_update.hpp) starts a loop of its own, after a barrier, and the next
//     stage starts another after a barrier.
// Every node sees the same operations in the same order as with one region per loop, so the
// results are the same bits, for any thread count.
#include <cstddef>
#include <functional>
#include <vector>

namespace talus {

enum class TileReach {
  OwnTile,  ///< reads and writes only the nodes of the tile it is given
  AnyTile,  ///< reads or writes nodes of other tiles (a ghost and its image)
};

class TileStages {
 public:
  using Stage = std::function<void(std::size_t)>;

  /// Stages over the `tiles` active tiles (their index in Grid::active_tiles).
  explicit TileStages(std::size_t tiles) : tiles_(tiles) {}

  /// A stage over the active tiles: stage(t) for t in [0, tiles).
  void add(TileReach reach, Stage stage);
  /// A stage over another index space (count items): a loop of its own, between barriers.
  void add_loop(std::size_t count, Stage stage);

  /// Runs the stages in one parallel region (nothing when there are none).
  void run() const;
  /// The loops run() holds: one fork/join and loops() - 1 barriers (0 when empty).
  int loops() const { return static_cast<int>(loops_.size()); }
  bool empty() const { return loops_.empty(); }

 private:
  struct Loop {
    std::size_t count = 0;
    bool own_tile = false;  // every stage of the loop is OwnTile over the active tiles
    std::vector<Stage> stages;
  };
  std::size_t tiles_;
  std::vector<Loop> loops_;
};

}  // namespace talus
