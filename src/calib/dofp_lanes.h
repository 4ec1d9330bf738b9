#pragma once
// Step 2's pass over one cell's observations in lanes (src/calib/dofp.cpp, accumulate_soa): the
// same source (dofp_lanes.inc) compiled for SSE2 and for AVX2 (without FMA, no contraction), with
// a fixed lane count of 8 and lane sums in lane order, so both give the same bits; the AVX2 one
// runs where the CPU has it. No Eigen here: the AVX2 file must not emit template code that the
// linker could pick for the SSE2 callers.
#include <cstddef>

namespace polrig::dofp_lanes {

inline constexpr int kLanes = 8;

struct Input {
  const double* L = nullptr;  // [4][28]: per pixel j, the 28 linear forms' coefficients
  const double* F = nullptr;  // F̃ by pixel: F[j·padded + i]
  const double *c = nullptr, *s = nullptr, *w = nullptr, *real = nullptr;  // per observation
  std::size_t padded = 0;     // a multiple of kLanes
  double c2psi = 1, s2psi = 0, dop_weight = 0, fit_weight = 0, d0 = 0;
  bool jacobian = true;
};

struct Output {
  double cost = 0, aop_ss = 0;
  double JtJ[8][8] = {};  // upper triangle
  double Jtr[8] = {};
};

// False (and `out` unusable) when an observation's AoP or DoP is undefined.
bool sums_sse2(const Input& in, Output& out);
bool sums_avx2(const Input& in, Output& out);

}  // namespace polrig::dofp_lanes
