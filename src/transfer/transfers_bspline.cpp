// The particle-grid transfers of the QuadraticBSplineShape, for every instruction set (shape_kernels_per_target.h).
#define TALUS_TRANSFER_SHAPE QuadraticBSplineShape
#include "transfer/shape_kernels_per_target.h"
