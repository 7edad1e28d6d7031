// The transfers' templates over (shape, terrain): each calls its shape's kernels at the instruction
// set in use (shape_kernels.hpp; the kernels themselves are in transfer_kernels-inl.h).
#include "talus/transfer/transfers.hpp"

#include "transfer/shape_kernels.hpp"

namespace talus {

template <class Shape, class Terrain>
void scatter_to_grid(const ParticleStore& P, const CellSort& sort, Grid& grid, ScatterFields fields,
                     ColourPassTiming* timing, BlockBuffers* buffers) {
  shape_kernels(std::type_identity<Shape>{}).scatter(!Terrain::kIsFlat, P, sort, grid, fields, buffers, timing);
}

template <class Shape, class Terrain>
GatherResult gather_from_grid(ParticleStore& P, const CellSort& sort, Grid& grid,
                              const std::array<std::span<double>, 3>& displacement, std::vector<double>& block_damping,
                              const GatherOptions& options, ColourPassTiming* timing, BlockBuffers* buffers) {
  return shape_kernels(std::type_identity<Shape>{}).gather(!Terrain::kIsFlat, P, sort, grid, displacement,
                                                           block_damping, options, buffers, timing);
}

template <class Shape, class Terrain>
void strain_increments(const ParticleStore& P, const Grid& grid, const NodeVectors& nv, double dt, std::size_t begin,
                       std::size_t end, StrainIncrements& out) {
  shape_kernels(std::type_identity<Shape>{}).strain(!Terrain::kIsFlat, P, grid, nv, dt, begin, end, out);
}

#define TALUS_INSTANTIATE_TRANSFERS(SHAPE, TERRAIN)                                                               \
  template void scatter_to_grid<SHAPE, TERRAIN>(const ParticleStore&, const CellSort&, Grid&, ScatterFields,       \
                                                ColourPassTiming*, BlockBuffers*);                                 \
  template GatherResult gather_from_grid<SHAPE, TERRAIN>(ParticleStore&, const CellSort&, Grid&,                     \
                                                         const std::array<std::span<double>, 3>&, std::vector<double>&, \
                                                         const GatherOptions&, ColourPassTiming*, BlockBuffers*);   \
  template void strain_increments<SHAPE, TERRAIN>(const ParticleStore&, const Grid&, const NodeVectors&, double,   \
                                                  std::size_t, std::size_t, StrainIncrements&);

TALUS_INSTANTIATE_TRANSFERS(LinearShape, FlatTerrain)
TALUS_INSTANTIATE_TRANSFERS(UGimpShape, FlatTerrain)
TALUS_INSTANTIATE_TRANSFERS(CpGimpShape, FlatTerrain)
TALUS_INSTANTIATE_TRANSFERS(QuadraticBSplineShape, FlatTerrain)
TALUS_INSTANTIATE_TRANSFERS(LinearShape, ProfileTerrain)
TALUS_INSTANTIATE_TRANSFERS(UGimpShape, ProfileTerrain)
TALUS_INSTANTIATE_TRANSFERS(CpGimpShape, ProfileTerrain)
TALUS_INSTANTIATE_TRANSFERS(QuadraticBSplineShape, ProfileTerrain)
#undef TALUS_INSTANTIATE_TRANSFERS

}  // namespace talus
