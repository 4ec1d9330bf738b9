#include "polrig/quadrature.h"

#include <Eigen/Dense>

#include <cmath>

namespace polrig {

QuadratureRule gauss_legendre_01(int n) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) J(k, k - 1) = J(k - 1, k) = k / std::sqrt(4.0 * k * k - 1.0);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(J);
  QuadratureRule r;
  for (int k = 0; k < n; ++k) {
    r.x.push_back(0.5 * (es.eigenvalues()(k) + 1.0));
    r.w.push_back(es.eigenvectors()(0, k) * es.eigenvectors()(0, k));  // 2·v₀², halved for [0, 1]
  }
  return r;
}

}  // namespace polrig
