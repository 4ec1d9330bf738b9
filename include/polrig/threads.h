#pragma once
// The threads polrig may use: the arena's concurrency within --threads (tbb::global_control,
// which limits TBB's workers but not what the arena says). For what sizes itself by it outside
// TBB's own loops (OpenEXR's pool, side_by_side.h's pieces in flight).

namespace polrig {

int usable_threads();

}  // namespace polrig
