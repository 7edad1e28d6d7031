#include "talus/grid/tile_stages.hpp"

#include <utility>

namespace talus {

void TileStages::add(TileReach reach, Stage stage) {
  const bool own = reach == TileReach::OwnTile;
  if (own && !loops_.empty() && loops_.back().own_tile) {
    loops_.back().stages.push_back(std::move(stage));
    return;
  }
  loops_.push_back({tiles_, own, {std::move(stage)}});
}

void TileStages::add_loop(std::size_t count, Stage stage) { loops_.push_back({count, false, {std::move(stage)}}); }

void TileStages::run() const {
  if (loops_.empty()) return;
  const std::size_t last = loops_.size() - 1;
#pragma omp parallel
  for (std::size_t l = 0; l <= last; ++l) {
    const Loop& loop = loops_[l];
    const auto count = loop.count;
#pragma omp for schedule(static) nowait
    for (std::size_t t = 0; t < count; ++t)
      for (const Stage& stage : loop.stages) stage(t);
    if (l < last) {  // after the last loop the region's end is the barrier
#pragma omp barrier
    }
  }
}

}  // namespace talus
