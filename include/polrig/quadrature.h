#pragma once
// Gauss–Legendre rules for the fixed-rule integrals of the traced source.
#include <vector>

namespace polrig {

struct QuadratureRule {
  std::vector<double> x, w;  // nodes and weights on [0, 1]; the weights sum to 1
};

// The n-point Gauss–Legendre rule on [0, 1] (Golub–Welsch: the eigenvalues of the Jacobi matrix,
// weights from the first components of its eigenvectors).
QuadratureRule gauss_legendre_01(int n);

}  // namespace polrig
