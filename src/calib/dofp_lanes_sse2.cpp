// dofp_lanes.h's SSE2 variant (the build's baseline instruction set).
#include "dofp_lanes.h"
#define POLRIG_DOFP_LANES_NAME sums_sse2
#include "dofp_lanes.inc"
