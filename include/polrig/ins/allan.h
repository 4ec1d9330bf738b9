#pragma once
// The overlapping Allan deviation of a rate series (IEEE 952; docs/physics.md §18.8).
// With θ_k = Σ_{i<k} y_i·Δt the integrated series and τ = m·Δt,
//   σ²(τ) = Σ_{k=0}^{N−2m} (θ_{k+2m} − 2θ_{k+m} + θ_k)² / (2τ²(N − 2m + 1)),
// at the octaves m = 1, 2, 4, … while N − 2m + 1 ≥ min_clusters.
#include <span>
#include <vector>

namespace polrig {

struct AllanPoint {
  double tau_s = 0;
  double adev = 0;
  long terms = 0;  // N − 2m + 1: the overlapping differences averaged
};

// Throws std::invalid_argument for Δt ≤ 0 or min_clusters < 1.
std::vector<AllanPoint> allan_deviation(std::span<const double> rate, double dt_s,
                                        long min_clusters = 9);

}  // namespace polrig
