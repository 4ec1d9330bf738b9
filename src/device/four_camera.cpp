#include "polrig/device/four_camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "four_camera_lanes.h"
#include "polrig/units.h"

namespace polrig {

std::array<double, 9> rotation_from_vector(const Vec3& r) {
  const double t = vec3::norm(r);
  if (t == 0.0) return {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const Vec3 a = vec3::mul(r, 1.0 / t);
  const double c = std::cos(t), s = std::sin(t), C = 1.0 - c;
  // R = c·I + s·[a]× + (1 − c)·a·aᵀ
  return {c + C * a[0] * a[0],        C * a[0] * a[1] - s * a[2], C * a[0] * a[2] + s * a[1],
          C * a[1] * a[0] + s * a[2], c + C * a[1] * a[1],        C * a[1] * a[2] - s * a[0],
          C * a[2] * a[0] - s * a[1], C * a[2] * a[1] + s * a[0], c + C * a[2] * a[2]};
}

Vec3 camera_position_mm(const FourCameraSpec& spec, int j) {
  static constexpr std::array<std::array<double, 2>, 4> corner = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
  const auto& c = corner.at(static_cast<std::size_t>(j));
  return {c[0] * spec.baseline_mm, c[1] * spec.baseline_mm, 0.0};
}

double kb_theta_d(const std::array<double, 4>& k, double theta) {
  const double t2 = theta * theta;
  return theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

namespace {
double kb_derivative(const std::array<double, 4>& k, double theta) {
  const double t2 = theta * theta;
  return 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
}
}  // namespace

double kb_theta(const std::array<double, 4>& k, double theta_d) {
  // Newton from θ = θ_d (exact for k = 0); θ_d is increasing over the field (four_camera_truth
  // checks it), so the iteration converges from there.
  double theta = theta_d;
  for (int i = 0; i < 50; ++i) {
    const double step = (kb_theta_d(k, theta) - theta_d) / kb_derivative(k, theta);
    theta -= step;
    if (std::abs(step) <= 1e-15 * (1.0 + theta)) break;
  }
  if (!(theta >= 0.0 && theta < std::numbers::pi) || std::abs(kb_theta_d(k, theta) - theta_d) > 1e-12)
    return std::numeric_limits<double>::quiet_NaN();
  return theta;
}

std::array<double, 2> project(const CameraGeometry& c, const Vec3& v) {
  if (!(v[2] > 0.0)) return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  const double rho = std::hypot(v[0], v[1]);
  if (rho == 0.0) return {c.cx, c.cy};
  const double theta = std::atan2(rho, v[2]);
  const double s = kb_theta_d(c.k, theta) / rho;
  return {c.fx * s * v[0] + c.cx, c.fy * s * v[1] + c.cy};
}

Vec3 unproject(const CameraGeometry& c, double u, double v) {
  const double x = (u - c.cx) / c.fx, y = (v - c.cy) / c.fy;
  const double theta_d = std::hypot(x, y);
  if (theta_d == 0.0) return {0, 0, 1};
  const double theta = kb_theta(c.k, theta_d);
  const double s = std::sin(theta) / theta_d;
  return {s * x, s * y, std::cos(theta)};
}

double four_camera_fov_x_deg(const FourCameraModel& m, int j) {
  const CameraGeometry& c = m.camera.at(static_cast<std::size_t>(j));
  return rad2deg(kb_theta(c.k, 0.5 * m.width / c.fx) * 2.0);
}
double four_camera_fov_y_deg(const FourCameraModel& m, int j) {
  const CameraGeometry& c = m.camera.at(static_cast<std::size_t>(j));
  return rad2deg(kb_theta(c.k, 0.5 * m.height / c.fy) * 2.0);
}

FourCameraModel four_camera_truth(const FourCameraSpec& spec) {
  if (spec.width_px < 2 || spec.height_px < 2)
    throw std::invalid_argument(fmt::format("four-camera image {} × {} px (expected at least 2 × 2)", spec.width_px,
                                            spec.height_px));
  FourCameraModel m;
  m.width = spec.width_px, m.height = spec.height_px;
  for (int j = 0; j < kFourCameras; ++j) {
    const auto J = static_cast<std::size_t>(j);
    CameraGeometry& c = m.camera[J];
    c.fx = spec.fx_px[J], c.fy = spec.fy_px[J], c.cx = spec.cx_px[J], c.cy = spec.cy_px[J];
    c.k = {spec.k1[J], spec.k2[J], spec.k3[J], spec.k4[J]};
    if (!(c.fx > 0 && c.fy > 0))
      throw std::invalid_argument(fmt::format("camera {}: f_x = {}, f_y = {} px (expected > 0)", j + 1, c.fx, c.fy));
    c.R = rotation_from_vector({deg2rad(spec.rot_x_deg[J]), deg2rad(spec.rot_y_deg[J]), deg2rad(spec.rot_z_deg[J])});
    if (!(spec.gain_DN[J] > 0))
      throw std::invalid_argument(fmt::format("camera {}: gain K = {} DN (expected > 0)", j + 1, spec.gain_DN[J]));
    m.K[J] = spec.gain_DN[J];
    m.b[J] = spec.offset_DN[J];
    m.axis_deg[J] = spec.polarizer_deg[J] + spec.eps_deg[J];
    // The lens must map angle to radius one to one over the image: θ_d increasing from the axis to
    // the farthest corner's radius (and a little beyond), with θ below 90° there.
    const double corner = std::hypot(std::max(c.cx, spec.width_px - c.cx) / c.fx,
                                     std::max(c.cy, spec.height_px - c.cy) / c.fy);
    double theta_end = 0;
    for (double t = 0; t <= 0.5 * std::numbers::pi; t += 1e-3)
      if (kb_theta_d(c.k, t) <= corner * 1.05) theta_end = t;
    for (double t = 0; t <= theta_end; t += 1e-3)
      if (!(kb_derivative(c.k, t) > 0))
        throw std::invalid_argument(fmt::format(
            "camera {}: the fisheye coefficients k = ({}, {}, {}, {}) fold the image (θ_d not increasing at θ = {:.1f}°)",
            j + 1, c.k[0], c.k[1], c.k[2], c.k[3], rad2deg(t)));
    if (!(kb_theta_d(c.k, 0.5 * std::numbers::pi - 1e-3) > corner))
      throw std::invalid_argument(fmt::format(
          "camera {}: the image's corner lies beyond 90° from the axis (f_x = {} px, f_y = {} px, k1 = {})", j + 1,
          c.fx, c.fy, c.k[0]));
  }
  if (spec.rot_x_deg[0] != 0 || spec.rot_y_deg[0] != 0 || spec.rot_z_deg[0] != 0)
    throw std::invalid_argument("camera 1's rotation relative to itself must be zero (device.rot_*_deg[0])");
  return m;
}

double image_plane_aop_rad(const Vec3& v, const Vec3& e) {
  // Frame i's axes turned by α (the view's azimuth) are the rotation taking ẑ to v applied to x̂
  // and ŷ: with g = 1/(1 + v_z), P = (1 − g·v_x², −g·v_x·v_y, −v_x), Q = (−g·v_x·v_y, 1 − g·v_y², −v_y);
  // φ_pix = atan2(e·Q, e·P) (the DoFP camera's image-plane analyzer, sim/dofp_frames.cpp).
  const double g = 1.0 / (1.0 + v[2]), gxy = g * v[0] * v[1];
  const double u = e[0] * (1.0 - g * v[0] * v[0]) - e[1] * gxy - e[2] * v[0];
  const double w = -e[0] * gxy + e[1] * (1.0 - g * v[1] * v[1]) - e[2] * v[1];
  return std::atan2(w, u);
}

std::array<double, 12> fusion_matrix(const PerCamera& axis_deg) {
  // DᵀD (3 × 3, symmetric) and its inverse by cofactors.
  std::array<std::array<double, 3>, 4> D{};
  for (std::size_t j = 0; j < 4; ++j) {
    const double a = 2.0 * deg2rad(axis_deg[j]);
    D[j] = {std::cos(a), std::sin(a), 1.0};
  }
  double M[3][3] = {};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (std::size_t j = 0; j < 4; ++j) M[r][c] += D[j][static_cast<std::size_t>(r)] * D[j][static_cast<std::size_t>(c)];
  const double c00 = M[1][1] * M[2][2] - M[1][2] * M[2][1], c01 = M[1][2] * M[2][0] - M[1][0] * M[2][2],
               c02 = M[1][0] * M[2][1] - M[1][1] * M[2][0];
  const double det = M[0][0] * c00 + M[0][1] * c01 + M[0][2] * c02;
  if (!(std::abs(det) > 1e-9))
    throw std::invalid_argument(fmt::format("polarizer axes {}°, {}°, {}°, {}°: DᵀD is singular (det {:.3g}); Eq. 4 needs "
                                            "three distinct axes mod 180°",
                                            axis_deg[0], axis_deg[1], axis_deg[2], axis_deg[3], det));
  double Inv[3][3];
  Inv[0][0] = c00 / det, Inv[0][1] = (M[0][2] * M[2][1] - M[0][1] * M[2][2]) / det,
  Inv[0][2] = (M[0][1] * M[1][2] - M[0][2] * M[1][1]) / det;
  Inv[1][0] = c01 / det, Inv[1][1] = (M[0][0] * M[2][2] - M[0][2] * M[2][0]) / det,
  Inv[1][2] = (M[0][2] * M[1][0] - M[0][0] * M[1][2]) / det;
  Inv[2][0] = c02 / det, Inv[2][1] = (M[0][1] * M[2][0] - M[0][0] * M[2][1]) / det,
  Inv[2][2] = (M[0][0] * M[1][1] - M[0][1] * M[1][0]) / det;
  std::array<double, 12> W{};
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t j = 0; j < 4; ++j)
      W[r * 4 + j] = Inv[r][0] * D[j][0] + Inv[r][1] * D[j][1] + Inv[r][2] * D[j][2];
  return W;
}

double FourCameraFusion::frame_offset_deg(int j, std::size_t i) const {
  if (j < 0 || j >= kFourCameras) throw std::out_of_range(fmt::format("camera {} (expected 0 to 3)", j));
  if (j == 0) {
    (void)offsets_.at(i);
    return 0.0;
  }
  const auto& o = offsets_.at(i);
  const auto J = static_cast<std::size_t>(2 * (j - 1));
  return rad2deg(0.5 * std::atan2(static_cast<double>(o[J + 1]), static_cast<double>(o[J])));
}

VirtualCamera virtual_camera(const FourCameraModel& m) {
  const CameraGeometry& c = m.camera[0];
  return {m.width, m.height, c.fx, c.cx, c.cy};
}

namespace {
// Eq. 4's (DᵀD)⁻¹ for the rows D_j = [D0_j, D1_j, 1]: the symmetric cofactors c00 … c22 over the
// determinant (fuse_at's and fusion_matrix's algebra).
struct NormalInverse {
  double c00, c01, c02, c11, c12, c22, inv;
};
NormalInverse normal_inverse(const std::array<double, 4>& D0, const std::array<double, 4>& D1) {
  double m00 = 0, m01 = 0, m02 = 0, m11 = 0, m12 = 0;
  for (std::size_t j = 0; j < 4; ++j)
    m00 += D0[j] * D0[j], m01 += D0[j] * D1[j], m02 += D0[j], m11 += D1[j] * D1[j], m12 += D1[j];
  const double m22 = 4.0;
  NormalInverse n;
  n.c00 = m11 * m22 - m12 * m12, n.c01 = m12 * m02 - m01 * m22, n.c02 = m01 * m12 - m11 * m02;
  n.c11 = m00 * m22 - m02 * m02, n.c12 = m02 * m01 - m00 * m12, n.c22 = m00 * m11 - m01 * m01;
  n.inv = 1.0 / (m00 * n.c00 + m01 * n.c01 + m02 * n.c02);
  return n;
}
}  // namespace

FourCameraFusion::FourCameraFusion(const FourCameraModel& model) : model_(model), grid_(virtual_camera(model)) {
  (void)fusion_matrix(model.axis_deg);  // refuses axes that cannot be fused
  for (std::size_t j = 0; j < 4; ++j) {
    cos2a_[j] = std::cos(2.0 * deg2rad(model.axis_deg[j]));
    sin2a_[j] = std::sin(2.0 * deg2rad(model.axis_deg[j]));
  }
  const int Wd = grid_.width, H = grid_.height;
  const std::size_t n = static_cast<std::size_t>(Wd) * static_cast<std::size_t>(H);
  const std::size_t K = detail::kFusionChunk;
  chunks_.resize((n + K - 1) / K);
  offsets_.resize(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int row = rows.begin(); row < rows.end(); ++row)
      for (int col = 0; col < Wd; ++col) {
        const std::size_t i = static_cast<std::size_t>(row) * static_cast<std::size_t>(Wd) + static_cast<std::size_t>(col);
        detail::FusionChunk& chunk = chunks_[i / K];
        const std::size_t k = i % K;
        const Vec3 p1 = {(col + 0.5 - grid_.cx) / grid_.f_c, (row + 0.5 - grid_.cy) / grid_.f_c, 1.0};
        std::array<double, 4> D0{}, D1{};
        for (std::size_t j = 0; j < 4; ++j) {
          const CameraGeometry& c = model.camera[j];
          const auto& R = c.R;
          const Vec3 pj = {R[0] * p1[0] + R[1] * p1[1] + R[2], R[3] * p1[0] + R[4] * p1[1] + R[5],
                           R[6] * p1[0] + R[7] * p1[1] + R[8]};
          const auto uv = project(c, pj);
          // δ_j: one E-vector ⊥ the ray (camera 1's P axis), its image-plane angle in both frames.
          double delta = 0;
          if (j > 0) {
            const Vec3 v1 = vec3::unit(p1), vj = vec3::unit(pj);
            const double g = 1.0 / (1.0 + v1[2]);
            const Vec3 e1 = {1.0 - g * v1[0] * v1[0], -g * v1[0] * v1[1], -v1[0]};
            const Vec3 ej = {R[0] * e1[0] + R[1] * e1[1] + R[2] * e1[2], R[3] * e1[0] + R[4] * e1[1] + R[5] * e1[2],
                             R[6] * e1[0] + R[7] * e1[1] + R[8] * e1[2]};
            delta = image_plane_aop_rad(v1, e1) - image_plane_aop_rad(vj, ej);
          }
          // Sample coordinates over the pixel centres: centre (col, row) at (col + ½, row + ½).
          const double x = uv[0] - 0.5, y = uv[1] - 0.5;
          std::int32_t index = -1;
          float wx = 0, wy = 0, c2 = 1, s2 = 0;
          if (x >= 0 && y >= 0 && x <= Wd - 1 && y <= H - 1) {
            const int x0 = std::min(static_cast<int>(x), Wd - 2), y0 = std::min(static_cast<int>(y), H - 2);
            index = y0 * Wd + x0, wx = static_cast<float>(x - x0), wy = static_cast<float>(y - y0);
            c2 = static_cast<float>(std::cos(2.0 * delta)), s2 = static_cast<float>(std::sin(2.0 * delta));
          }
          chunk.index[j][k] = index, chunk.wx[j][k] = wx, chunk.wy[j][k] = wy;
          if (j > 0) offsets_[i][2 * j - 2] = c2, offsets_[i][2 * j - 1] = s2;
          // D_j = [cos 2(a_j + δ_j), sin 2(a_j + δ_j), 1] from the stored cos 2δ_j, sin 2δ_j (as fuse_at).
          D0[j] = cos2a_[j] * c2 - sin2a_[j] * s2;
          D1[j] = sin2a_[j] * c2 + cos2a_[j] * s2;
        }
        // W = (DᵀD)⁻¹Dᵀ, columns 1–3 of each row (its rows sum to 0, 0, 1).
        const NormalInverse m = normal_inverse(D0, D1);
        for (std::size_t j = 0; j < 3; ++j) {
          chunk.W[j][k] = static_cast<float>((m.c00 * D0[j] + m.c01 * D1[j] + m.c02) * m.inv);
          chunk.W[3 + j][k] = static_cast<float>((m.c01 * D0[j] + m.c11 * D1[j] + m.c12) * m.inv);
          chunk.W[6 + j][k] = static_cast<float>((m.c02 * D0[j] + m.c12 * D1[j] + m.c22) * m.inv);
        }
      }
  });
  // The last chunk's pixels beyond the image: not seen.
  for (std::size_t i = n; i < chunks_.size() * K; ++i)
    for (std::size_t j = 0; j < 4; ++j) chunks_[i / K].index[j][i % K] = -1;
}

template <class T>
bool FourCameraFusion::fuse_at(const std::array<std::span<const T>, kFourCameras>& frames, std::size_t i,
                               FusedStokes& x) const {
  const std::size_t w = static_cast<std::size_t>(grid_.width);
  const detail::FusionChunk& chunk = chunks_[i / detail::kFusionChunk];
  const std::size_t k = i % detail::kFusionChunk;
  std::array<double, 4> F{}, D0{}, D1{};
  for (std::size_t j = 0; j < 4; ++j) {
    // D_j = [cos 2(a_j + δ_j), sin 2(a_j + δ_j), 1].
    const double c2 = j == 0 ? 1.0 : offsets_[i][2 * j - 2], s2 = j == 0 ? 0.0 : offsets_[i][2 * j - 1];
    D0[j] = cos2a_[j] * c2 - sin2a_[j] * s2;
    D1[j] = sin2a_[j] * c2 + cos2a_[j] * s2;
    if (chunk.index[j][k] < 0) return false;
    const T* p = frames[j].data() + chunk.index[j][k];
    const double wx = chunk.wx[j][k], wy = chunk.wy[j][k];
    const double top = static_cast<double>(p[0]) + wx * (static_cast<double>(p[1]) - static_cast<double>(p[0]));
    const double bottom = static_cast<double>(p[w]) + wx * (static_cast<double>(p[w + 1]) - static_cast<double>(p[w]));
    F[j] = (top + wy * (bottom - top) - model_.b[j]) / model_.K[j];
  }
  // Eq. 4: (DᵀD)·x = Dᵀ·F, DᵀD symmetric 3 × 3, by cofactors (the same algebra as fusion_matrix).
  double r0 = 0, r1 = 0, r2 = 0;
  for (std::size_t j = 0; j < 4; ++j) r0 += D0[j] * F[j], r1 += D1[j] * F[j], r2 += F[j];
  const NormalInverse m = normal_inverse(D0, D1);
  x.S1 = (m.c00 * r0 + m.c01 * r1 + m.c02 * r2) * m.inv;
  x.S2 = (m.c01 * r0 + m.c11 * r1 + m.c12 * r2) * m.inv;
  x.S0 = (m.c02 * r0 + m.c12 * r1 + m.c22 * r2) * m.inv;
  return true;
}

template <class T>
FusedImage FourCameraFusion::fuse(const std::array<std::span<const T>, kFourCameras>& frames) const {
  const int Wd = grid_.width, H = grid_.height;
  const std::size_t n = static_cast<std::size_t>(Wd) * static_cast<std::size_t>(H);
  for (std::size_t j = 0; j < 4; ++j)
    if (frames[j].size() != n)
      throw std::invalid_argument(fmt::format("camera {}'s frame has {} pixels (expected {} × {})", j + 1,
                                              frames[j].size(), Wd, H));
  FusedImage out;
  out.grid = grid_;
  // The layers' 17 MB (at W16's size) are zeroed and their pages faulted in as they are made: on
  // every thread, not serially before the fusion.
  tbb::parallel_invoke([&] { out.S0.resize(n); }, [&] { out.S1.resize(n); }, [&] { out.S2.resize(n); },
                       [&] { out.AoP.resize(n); }, [&] { out.DoP.resize(n); }, [&] { out.valid.resize(n); });
  four_camera_lanes::Constants k;
  k.width = static_cast<std::size_t>(Wd);
  for (std::size_t j = 0; j < 4; ++j) {
    k.b[j] = static_cast<float>(model_.b[j]);
    k.inv_K[j] = static_cast<float>(1.0 / model_.K[j]);
  }
  const T* const f[4] = {frames[0].data(), frames[1].data(), frames[2].data(), frames[3].data()};
  const std::size_t K = detail::kFusionChunk, whole = n / K;
  const auto layers_at = [&](std::size_t chunk) {
    const std::size_t o = chunk * K;
    return four_camera_lanes::Layers{out.S0.data() + o,  out.S1.data() + o,  out.S2.data() + o,
                                     out.AoP.data() + o, out.DoP.data() + o, out.valid.data() + o};
  };
  // Each pixel's layers depend on that pixel alone: the same bits for any partition.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, whole, 32), [&](const tbb::blocked_range<std::size_t>& r) {
    four_camera_lanes::fuse_chunks(chunks_.data() + r.begin(), r.size(), f, k, layers_at(r.begin()));
  });
  if (whole < chunks_.size()) {  // the last, partial chunk through a whole one
    const std::size_t m = n - whole * K;
    float S0[K], S1[K], S2[K], AoP[K], DoP[K];
    std::uint8_t valid[K];
    four_camera_lanes::fuse_chunks(chunks_.data() + whole, 1, f, k, {S0, S1, S2, AoP, DoP, valid});
    const std::size_t o = whole * K;
    std::copy_n(S0, m, out.S0.data() + o), std::copy_n(S1, m, out.S1.data() + o), std::copy_n(S2, m, out.S2.data() + o);
    std::copy_n(AoP, m, out.AoP.data() + o), std::copy_n(DoP, m, out.DoP.data() + o);
    std::copy_n(valid, m, out.valid.data() + o);
  }
  return out;
}

template bool FourCameraFusion::fuse_at<std::uint16_t>(const std::array<std::span<const std::uint16_t>, kFourCameras>&,
                                                       std::size_t, FusedStokes&) const;
template bool FourCameraFusion::fuse_at<double>(const std::array<std::span<const double>, kFourCameras>&, std::size_t,
                                                FusedStokes&) const;
template FusedImage FourCameraFusion::fuse<std::uint16_t>(
    const std::array<std::span<const std::uint16_t>, kFourCameras>&) const;
template FusedImage FourCameraFusion::fuse<double>(const std::array<std::span<const double>, kFourCameras>&) const;

DofpCameraSpec exposure_spec(const FourCameraSpec& spec) {
  DofpCameraSpec e;
  e.noise = spec.noise;
  e.electrons_per_DN = spec.electrons_per_DN;
  e.read_noise_DN = spec.read_noise_DN;
  e.adc_bits = spec.adc_bits;
  return e;
}

}  // namespace polrig
