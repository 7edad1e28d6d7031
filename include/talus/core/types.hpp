#pragma once
// Small shared types. Conventions (see docs/theory.md):
//  - SI units everywhere.
//  - Stress positive in tension.
//  - Symmetric tensors as Voigt 6-vectors in the order xx, yy, zz, yz, xz, xy holding TENSOR
//    components (eps_yz, not the engineering gamma_yz = 2 eps_yz). Contractions therefore weight
//    the last three entries by 2 (see tensor.hpp).
//  - Spin increments as the 3 independent components (w_yz, w_xz, w_xy) of the antisymmetric
//    tensor dW = dt/2 (L - L^T), W_ij = 1/2 (dv_i/dx_j - dv_j/dx_i).
#include <Eigen/Core>
#include <cstdint>

namespace talus {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Sym6 = Eigen::Matrix<double, 6, 1>;

enum Voigt : int { XX = 0, YY = 1, ZZ = 2, YZ = 3, XZ = 4, XY = 5 };

}  // namespace talus
