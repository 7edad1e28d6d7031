// The body of transfers_<shape>.cpp: the transfer kernels (transfer_kernels-inl.h) of the shape
// TALUS_TRANSFER_SHAPE, compiled once per instruction set by Highway's foreach_target (which includes
// this file again for each target) and dispatched at run time: shape_kernels() (shape_kernels.hpp).
#ifndef TALUS_TRANSFER_SHAPE
#error "define TALUS_TRANSFER_SHAPE (the shape function type) before including shape_kernels_per_target.h"
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "transfer/shape_kernels_per_target.h"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "talus/core/simd_dispatch.hpp"
#include "transfer/shape_kernels.hpp"
#include "transfer/transfer_kernels-inl.h"

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace {  // this file's shape only: every shape's file defines these names

void ScatterToGrid(bool profile, const ParticleStore& P, const CellSort& sort, Grid& grid, ScatterFields fields,
                   BlockBuffers* buffers, ColourPassTiming* timing) {
  if (profile)
    scatter_impl<TALUS_TRANSFER_SHAPE, ProfileTerrain>(P, sort, grid, fields, buffers, timing);
  else
    scatter_impl<TALUS_TRANSFER_SHAPE, FlatTerrain>(P, sort, grid, fields, buffers, timing);
}

GatherResult GatherFromGrid(bool profile, ParticleStore& P, const CellSort& sort, Grid& grid,
                            const std::array<std::span<double>, 3>& displacement, std::vector<double>& block_damping,
                            const GatherOptions& options, BlockBuffers* buffers, ColourPassTiming* timing) {
  return profile ? gather_impl<TALUS_TRANSFER_SHAPE, ProfileTerrain>(P, sort, grid, displacement, block_damping,
                                                                     options, buffers, timing)
                 : gather_impl<TALUS_TRANSFER_SHAPE, FlatTerrain>(P, sort, grid, displacement, block_damping,
                                                                  options, buffers, timing);
}

void StrainIncrementsOf(bool profile, const ParticleStore& P, const Grid& grid, const NodeVectors& nv, double dt,
                        std::size_t begin, std::size_t end, StrainIncrements& out) {
  if (profile)
    strain_impl<TALUS_TRANSFER_SHAPE, ProfileTerrain>(P, grid, nv, dt, begin, end, out);
  else
    strain_impl<TALUS_TRANSFER_SHAPE, FlatTerrain>(P, grid, nv, dt, begin, end, out);
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace talus {

HWY_EXPORT(ScatterToGrid);
HWY_EXPORT(GatherFromGrid);
HWY_EXPORT(StrainIncrementsOf);

// The `reference` path runs the baseline build of the same code.
#define TALUS_TRANSFER_DISPATCH(FUNC) (vector_kernels_enabled() ? HWY_DYNAMIC_DISPATCH(FUNC) : &HWY_STATIC_DISPATCH(FUNC))

ShapeKernels shape_kernels(std::type_identity<TALUS_TRANSFER_SHAPE>) {
  return {TALUS_TRANSFER_DISPATCH(ScatterToGrid), TALUS_TRANSFER_DISPATCH(GatherFromGrid),
          TALUS_TRANSFER_DISPATCH(StrainIncrementsOf)};
}

#undef TALUS_TRANSFER_DISPATCH
}  // namespace talus
#endif
