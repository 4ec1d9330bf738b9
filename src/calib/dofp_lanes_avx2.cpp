// dofp_lanes.h's AVX2 variant: this file alone is compiled with -mavx2 -mno-fma
// -ffp-contract=off (CMakeLists.txt); dofp.cpp calls it only where the CPU has AVX2.
#include "dofp_lanes.h"
#define POLRIG_DOFP_LANES_NAME sums_avx2
#include "dofp_lanes.inc"
