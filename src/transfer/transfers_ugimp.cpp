// The particle-grid transfers of the UGimpShape, for every instruction set (shape_kernels_per_target.h).
#define TALUS_TRANSFER_SHAPE UGimpShape
#include "transfer/shape_kernels_per_target.h"
