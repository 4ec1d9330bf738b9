#pragma once
// FourCameraFusion::fuse's kernel over whole chunks of virtual pixels (four_camera_lanes.cpp): the
// four bilinear samples, Eq. 4 with the chunk's precomputed W and Eq. 5 (AoP, DoP) in float SIMD
// lanes, the same bits on every code path.
#include <cstddef>
#include <cstdint>

#include "polrig/device/four_camera.h"

namespace polrig::four_camera_lanes {

struct Constants {
  std::size_t width = 0;         // a frame's row length (the tap below index is index + width)
  float b[kFourCameras] = {};    // offsets b_j (DN)
  float inv_K[kFourCameras] = {};  // 1/K_j
};

// Where chunk 0's layers go (kFusionChunk values per chunk and layer, consecutive).
struct Layers {
  float *S0 = nullptr, *S1 = nullptr, *S2 = nullptr, *AoP = nullptr, *DoP = nullptr;
  std::uint8_t* valid = nullptr;
};

// The layers of `count` consecutive chunks; the best code path unless set_baseline_paths_only
// (polrig/vector_log.h) is on.
void fuse_chunks(const detail::FusionChunk* chunks, std::size_t count, const std::uint16_t* const frames[kFourCameras],
                 const Constants& c, const Layers& out);
void fuse_chunks(const detail::FusionChunk* chunks, std::size_t count, const double* const frames[kFourCameras],
                 const Constants& c, const Layers& out);

}  // namespace polrig::four_camera_lanes
