#pragma once
// The fixed-interval Rauch–Tung–Striebel smoother of a closed-loop (feedback) error-state Kalman
// filter (docs/physics.md §18.7; Rauch, Tung & Striebel 1965; Brown & Hwang 2012 §6.2 for the
// open-loop form). A closed-loop filter feeds every update's estimate δ_k = K_k·ν_k back into its
// state and restarts from x = 0, so its x⁺_k is 0 and its x⁻_{k+1} = Φ x⁺_k is 0 too. The smoothed
// error y_k (the correction still to add to the filtered state at epoch k) then follows from the
// open-loop recursion x̂ˢ_k = x̂⁺_k + C_k (x̂ˢ_{k+1} − x̂⁻_{k+1}) with every estimate measured from
// the state the filter held, that of epoch k+1 being δ_{k+1} before the filtered one:
//   y_N = 0,   y_k = C_k·(δ_{k+1} + y_{k+1}),   C_k = P⁺_k Φ_kᵀ (P⁻_{k+1})⁻¹,
//   Pˢ_N = P⁺_N,   Pˢ_k = P⁺_k + C_k (Pˢ_{k+1} − P⁻_{k+1}) C_kᵀ,
// with Φ_k the transition from epoch k to k+1. Sizes are the caller's (ins/ uses 15 states).
#include <vector>

#include <Eigen/Core>

namespace polrig {

// Epoch k of a closed-loop filter run, as the smoother needs it.
struct FilterRecord {
  Eigen::MatrixXd Phi;         // Φ from the previous epoch to this one (unused at the first)
  Eigen::MatrixXd P_prior;     // P⁻_k, before this epoch's update
  Eigen::MatrixXd P_post;      // P⁺_k, after it
  Eigen::VectorXd correction;  // δ_k, what the update fed back (0 without one)
};

struct SmoothedEpoch {
  Eigen::VectorXd correction;  // y_k: add to the filtered state at epoch k (as the filter's feedback does)
  Eigen::MatrixXd P;           // Pˢ_k
};

// The backward pass over a whole run (records[0] the first epoch). (P⁻_{k+1})⁻¹ is applied by an
// LDLᵀ solve that treats zero pivots as zero (a state the filter holds fixed, such as a held
// height, has no variance and gets no correction). Throws std::invalid_argument for records of
// inconsistent sizes.
std::vector<SmoothedEpoch> rts_smooth(const std::vector<FilterRecord>& records);

}  // namespace polrig
