#include "polrig/ins/smoother.h"

#include <stdexcept>

#include <Eigen/Cholesky>
#include <fmt/format.h>

namespace polrig {

std::vector<SmoothedEpoch> rts_smooth(const std::vector<FilterRecord>& records) {
  std::vector<SmoothedEpoch> out(records.size());
  if (records.empty()) return out;
  const Eigen::Index n = records.back().P_post.rows();
  for (std::size_t k = 0; k < records.size(); ++k) {
    const FilterRecord& r = records[k];
    const bool sized = r.P_prior.rows() == n && r.P_prior.cols() == n && r.P_post.rows() == n && r.P_post.cols() == n &&
                       r.correction.size() == n && (k == 0 || (r.Phi.rows() == n && r.Phi.cols() == n));
    if (!sized) throw std::invalid_argument(fmt::format("RTS smoother: epoch {}'s matrices are not all {} × {}", k, n, n));
  }
  const std::size_t N = records.size() - 1;
  out[N] = {Eigen::VectorXd::Zero(n), records[N].P_post};
  for (std::size_t k = N; k-- > 0;) {
    const FilterRecord& next = records[k + 1];
    // C_kᵀ = (P⁻_{k+1})⁻¹ Φ_k P⁺_k (P⁻ and P⁺ symmetric).
    const Eigen::MatrixXd Ct = next.P_prior.ldlt().solve(next.Phi * records[k].P_post);
    const Eigen::MatrixXd C = Ct.transpose();
    out[k].correction = C * (next.correction + out[k + 1].correction);
    Eigen::MatrixXd P = records[k].P_post + C * (out[k + 1].P - next.P_prior) * Ct;
    out[k].P = 0.5 * (P + P.transpose());
  }
  return out;
}

}  // namespace polrig
