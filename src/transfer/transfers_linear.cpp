// The particle-grid transfers of the LinearShape, for every instruction set (shape_kernels_per_target.h).
#define TALUS_TRANSFER_SHAPE LinearShape
#include "transfer/shape_kernels_per_target.h"
