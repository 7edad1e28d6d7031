#pragma once
// The transfer kernels of one shape function, for both terrain types, at the instruction set in use
// (core/simd_dispatch.hpp). Each shape's kernels are compiled in a file of their own
// (transfers_<shape>.cpp, through shape_kernels_per_target.h), so that the four compile in parallel:
// compiled once per instruction set, they are the longest part of the build.
#include "talus/shape/bspline.hpp"
#include "talus/shape/gimp.hpp"
#include "talus/shape/linear.hpp"
#include "talus/transfer/transfers.hpp"

#include <type_traits>

namespace talus {

/// Entry points taking the terrain type as a flag: `profile` for ProfileTerrain, else FlatTerrain.
struct ShapeKernels {
  void (*scatter)(bool profile, const ParticleStore& particles, const CellSort& sort, Grid& grid, ScatterFields fields,
                  BlockBuffers* buffers, ColourPassTiming* timing);
  GatherResult (*gather)(bool profile, ParticleStore& particles, const CellSort& sort, Grid& grid,
                         const std::array<std::span<double>, 3>& displacement, std::vector<double>& block_damping,
                         const GatherOptions& options, BlockBuffers* buffers, ColourPassTiming* timing);
  void (*strain)(bool profile, const ParticleStore& particles, const Grid& grid, const NodeVectors& node_velocity,
                 double dt, std::size_t begin, std::size_t end, StrainIncrements& out);
};

ShapeKernels shape_kernels(std::type_identity<LinearShape>);            // transfers_linear.cpp
ShapeKernels shape_kernels(std::type_identity<UGimpShape>);             // transfers_ugimp.cpp
ShapeKernels shape_kernels(std::type_identity<CpGimpShape>);            // transfers_cpgimp.cpp
ShapeKernels shape_kernels(std::type_identity<QuadraticBSplineShape>);  // transfers_bspline.cpp

}  // namespace talus
