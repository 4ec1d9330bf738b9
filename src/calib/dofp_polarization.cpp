#include "polrig/calib/dofp_polarization.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

namespace polrig {

DofpTruth nominal_dofp_parameters(int width, int height, const std::array<double, 4>& mosaic_deg) {
  if (width <= 0 || height <= 0 || width % 2 || height % 2)
    throw std::invalid_argument(fmt::format("DoFP frame {} × {}: expected even, positive sizes", width, height));
  const std::size_t n = static_cast<std::size_t>(width) * height;
  DofpTruth t;
  t.width = width;
  t.height = height;
  t.K.assign(n, 1.0);
  t.b.assign(n, 0.0);
  t.k.assign(n, 1.0);
  t.eps_deg.assign(n, 0.0);
  t.alpha_deg.resize(n);
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col)
      t.alpha_deg[static_cast<std::size_t>(row) * width + col] = mosaic_deg[static_cast<std::size_t>((row % 2) * 2 + col % 2)];
  return t;
}

DofpCellPolarization dofp_cell_polarization(std::span<const double> frame, const DofpTruth& p) {
  const int width = p.width, height = p.height;
  const std::size_t n = static_cast<std::size_t>(width) * height;
  if (width <= 0 || height <= 0 || width % 2 || height % 2)
    throw std::invalid_argument(fmt::format("DoFP frame {} × {}: expected even, positive sizes", width, height));
  if (frame.size() != n || p.K.size() != n || p.b.size() != n || p.k.size() != n || p.eps_deg.size() != n ||
      p.alpha_deg.size() != n)
    throw std::invalid_argument(fmt::format("DoFP frame of {} values and parameters of {} × {} pixels do not match",
                                            frame.size(), width, height));
  DofpCellPolarization out;
  out.cells_x = width / 2;
  out.cells_y = height / 2;
  const std::size_t cells = n / 4;
  out.S0.resize(cells);
  out.aop_deg.resize(cells);
  out.dop.resize(cells);
  for (std::size_t q = 0; q < n; ++q)
    if (!(p.K[q] >= 0) || !std::isfinite(p.K[q]) || !std::isfinite(p.b[q]) || !std::isfinite(p.k[q]) ||
        !std::isfinite(p.eps_deg[q]))
      throw std::invalid_argument(fmt::format("DoFP parameters: pixel ({}, {}) has K = {}, b = {}, k = {}, eps = {}° "
                                              "(expected K ≥ 0 and finite values)",
                                              q % width, q / width, p.K[q], p.b[q], p.k[q], p.eps_deg[q]));
  constexpr double kDeg = std::numbers::pi / 180.0;
  std::vector<unsigned char> singular(cells, 0);  // checked after the loop: the first one is reported
  tbb::parallel_for(0, out.cells_y, [&](int cy) {
    for (int cx = 0; cx < out.cells_x; ++cx) {
      const std::size_t r0 = static_cast<std::size_t>(2 * cy) * width + 2 * cx;
      const std::size_t px[4] = {r0, r0 + 1, r0 + width, r0 + width + 1};
      const std::size_t c = static_cast<std::size_t>(cy) * out.cells_x + cx;
      constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
      if (p.K[px[0]] == 0 || p.K[px[1]] == 0 || p.K[px[2]] == 0 || p.K[px[3]] == 0) {
        out.S0[c] = out.aop_deg[c] = out.dop[c] = kNaN;  // step 1 left a pixel undetermined (K = 0)
        continue;
      }
      Eigen::Matrix<double, 4, 3> A;
      Eigen::Vector4d F;
      for (int j = 0; j < 4; ++j) {
        const std::size_t q = px[j];
        const double a = 2.0 * (p.alpha_deg[q] - p.eps_deg[q]) * kDeg;
        A.row(j) << p.k[q] * std::cos(a), p.k[q] * std::sin(a), 1.0;
        F[j] = (frame[q] - p.b[q]) / p.K[q];
      }
      const Eigen::Matrix3d R = A.transpose() * A;
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(R);
      if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * ldlt.vectorD().maxCoeff())) {
        singular[c] = 1;
        continue;
      }
      const Eigen::Vector3d Q = ldlt.solve(A.transpose() * F);
      const double lin = std::hypot(Q[0], Q[1]);
      out.S0[c] = 2.0 * Q[2];
      double aop = lin > 0 ? 0.5 * std::atan2(Q[1], Q[0]) / kDeg : std::numeric_limits<double>::quiet_NaN();
      if (aop < 0) aop += 180.0;
      out.aop_deg[c] = aop;
      out.dop[c] = Q[2] > 0 ? lin / Q[2] : std::numeric_limits<double>::quiet_NaN();
    }
  });
  for (std::size_t c = 0; c < cells; ++c)
    if (singular[c])
      throw std::invalid_argument(fmt::format("DoFP parameters: the analyzers of cell ({}, {}) do not span the "
                                              "Stokes plane", c % out.cells_x, c / out.cells_x));
  return out;
}

}  // namespace polrig
