// The particle-grid transfers of the CpGimpShape, for every instruction set (shape_kernels_per_target.h).
#define TALUS_TRANSFER_SHAPE CpGimpShape
#include "transfer/shape_kernels_per_target.h"
