#include "polrig/sim/four_camera_frames.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "polrig/random.h"
#include "polrig/sky/sensor_view.h"
#include "polrig/units.h"

namespace polrig {

namespace {
// M = [A.x A.y A.z]·R_j1ᵀ: a direction in camera j's frame to the rig frame (row-major).
std::array<double, 9> camera_to_rig(const InstrumentAxes& A, const std::array<double, 9>& R) {
  std::array<double, 9> M{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      // (Rᵀ)[k][c] = R[c][k]; camera 1's axis k in the rig frame: A.x, A.y, A.z.
      double s = 0;
      for (int k = 0; k < 3; ++k) {
        const Vec3& axis = k == 0 ? A.x : k == 1 ? A.y : A.z;
        s += axis[static_cast<std::size_t>(r)] * R[static_cast<std::size_t>(c * 3 + k)];
      }
      M[static_cast<std::size_t>(r * 3 + c)] = s;
    }
  return M;
}
}  // namespace

FourCameraSimulator::FourCameraSimulator(const Rig& rig) : rig_(rig) {
  if (!rig.instrument().has(Instrument::kCameraArray))
    throw std::invalid_argument(
        fmt::format("device.kind {} is not a camera array (expected four-camera)", rig.device_kind));
  check_camera_light(rig);
  truth_ = four_camera_truth(rig.four_camera);
  fusion_ = std::make_shared<const FourCameraFusion>(truth_);
  noise_seed_ = derive_seed(rig.seed, 2);
  stops_ = dofp_stops(rig.schedule);
  const int W = truth_.width, H = truth_.height;
  const std::size_t n = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  for (std::size_t j = 0; j < 4; ++j) {
    views_[j].resize(n);
    const CameraGeometry& c = truth_.camera[j];
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
      for (int row = rows.begin(); row < rows.end(); ++row)
        for (int col = 0; col < W; ++col)
          views_[j][static_cast<std::size_t>(row) * static_cast<std::size_t>(W) + static_cast<std::size_t>(col)] =
              unproject(c, col + 0.5, row + 0.5);
    });
  }
}

FourCameraSignal FourCameraSimulator::signal(const DofpStop& stop) const {
  const int W = truth_.width, H = truth_.height;
  const std::size_t n = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  const std::unique_ptr<const LightAlongViews> light =
      rig_.light->light_along_views(rig_.source_view(), {stop.theta_R_deg, stop.t_s});
  FourCameraSignal out{stop, {}};
  for (std::size_t j = 0; j < 4; ++j) {
    out.f[j].resize(n);
    const std::array<double, 9> M = camera_to_rig(light->axes, truth_.camera[j].R);
    const double K = truth_.K[j], b = truth_.b[j], a2 = 2.0 * deg2rad(truth_.axis_deg[j]);
    const double ca = std::cos(a2), sa = std::sin(a2);
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
      const std::size_t w = static_cast<std::size_t>(W);
      std::vector<Vec3> rig_views(w);
      std::vector<ViewLight> lights(w);
      for (int row = rows.begin(); row < rows.end(); ++row) {
        const std::size_t first = static_cast<std::size_t>(row) * w;
        const Vec3* v = views_[j].data() + first;
        for (std::size_t c = 0; c < w; ++c)
          rig_views[c] = {M[0] * v[c][0] + M[1] * v[c][1] + M[2] * v[c][2],
                          M[3] * v[c][0] + M[4] * v[c][1] + M[5] * v[c][2],
                          M[6] * v[c][0] + M[7] * v[c][1] + M[8] * v[c][2]};
        light->along(rig_views, lights);
        double* f = out.f[j].data() + first;
        for (std::size_t c = 0; c < w; ++c) {
          const ViewLight& L = lights[c];
          // e in camera j's frame: Mᵀ·e.
          const Vec3 e = {M[0] * L.e[0] + M[3] * L.e[1] + M[6] * L.e[2], M[1] * L.e[0] + M[4] * L.e[1] + M[7] * L.e[2],
                          M[2] * L.e[0] + M[5] * L.e[1] + M[8] * L.e[2]};
          const double I = L.S0 * stop.intensity, d = stop.polarized ? L.d : 0.0;
          double cos2 = 1.0, sin2 = 0.0;
          if (d > 0) {
            const double phi = image_plane_aop_rad(v[c], e);
            cos2 = std::cos(2.0 * phi), sin2 = std::sin(2.0 * phi);
          }
          // Eq. 1: K·I·[1 + d·cos(2φ − 2a)] + b, cos(2φ − 2a) = cos 2φ·cos 2a + sin 2φ·sin 2a.
          f[c] = K * I * (1.0 + d * (cos2 * ca + sin2 * sa)) + b;
        }
      }
    });
  }
  return out;
}

std::array<std::vector<std::uint16_t>, kFourCameras> FourCameraSimulator::frames(const FourCameraSignal& signal,
                                                                                 int frame) const {
  std::array<std::vector<std::uint16_t>, kFourCameras> raw;
  const DofpCameraSpec noise = exposure_spec(rig_.four_camera);
  for (std::size_t j = 0; j < 4; ++j) {
    const std::size_t n = signal.f[j].size();
    raw[j].resize(n);
    const DofpExposure expose(noise, noise_seed_, static_cast<std::uint64_t>(signal.stop.index),
                              static_cast<std::uint64_t>(frame) * 4 + j);
    const double* f = signal.f[j].data();
    const double b = truth_.b[j];
    std::uint16_t* out = raw[j].data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) out[i] = expose(f[i], b, i);
    });
  }
  return raw;
}

FusedImage FourCameraSimulator::fuse(const std::array<std::vector<std::uint16_t>, kFourCameras>& raw) const {
  return fusion_->fuse<std::uint16_t>({raw[0], raw[1], raw[2], raw[3]});
}

FusedImage FourCameraSimulator::fuse(const FourCameraSignal& signal) const {
  return fusion_->fuse<double>({signal.f[0], signal.f[1], signal.f[2], signal.f[3]});
}

FourCameraTruthLayers FourCameraSimulator::truth_on_grid(const DofpStop& stop) const {
  const VirtualCamera g = fusion_->grid();
  const std::size_t n = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  const std::unique_ptr<const LightAlongViews> light =
      rig_.light->light_along_views(rig_.source_view(), {stop.theta_R_deg, stop.t_s});
  const InstrumentAxes& A = light->axes;
  FourCameraTruthLayers t;
  for (auto* v : {&t.S0, &t.S1, &t.S2, &t.AoP, &t.DoP}) v->resize(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, g.height, 4), [&](const tbb::blocked_range<int>& rows) {
    const std::size_t w = static_cast<std::size_t>(g.width);
    std::vector<Vec3> v1(w), rig_views(w);
    std::vector<ViewLight> lights(w);
    for (int row = rows.begin(); row < rows.end(); ++row) {
      for (std::size_t c = 0; c < w; ++c) {
        v1[c] = vec3::unit({(static_cast<double>(c) + 0.5 - g.cx) / g.f_c, (row + 0.5 - g.cy) / g.f_c, 1.0});
        rig_views[c] = vec3::add(vec3::add(vec3::mul(A.x, v1[c][0]), vec3::mul(A.y, v1[c][1])), vec3::mul(A.z, v1[c][2]));
      }
      light->along(rig_views, lights);
      for (std::size_t c = 0; c < w; ++c) {
        const std::size_t i = static_cast<std::size_t>(row) * w + c;
        const ViewLight& L = lights[c];
        const Vec3 e = {vec3::dot(L.e, A.x), vec3::dot(L.e, A.y), vec3::dot(L.e, A.z)};
        const double I = L.S0 * stop.intensity, d = stop.polarized ? L.d : 0.0;
        const double phi = d > 0 ? image_plane_aop_rad(v1[c], e) : 0.0;
        double aop = rad2deg(phi);
        aop -= 180.0 * std::floor(aop / 180.0);
        t.S0[i] = I, t.S1[i] = I * d * std::cos(2 * phi), t.S2[i] = I * d * std::sin(2 * phi);
        t.AoP[i] = aop >= 180.0 ? 0.0 : aop, t.DoP[i] = d;
      }
    }
  });
  return t;
}

std::optional<Vec3> FourCameraSimulator::sun_in_camera1(const DofpStop& stop) const {
  const std::optional<Sky> sky = rig_sky(rig_);
  if (!sky) return std::nullopt;
  const SkyMount mount = rig_.source.sky.resolved_mount();
  const SunPosition sun =
      sun_position(sky->first_stop.plus_seconds(stop.t_s + mount.time_offset_s), sky->site, sky->sun);
  const Vec3 s = sun_direction_enu(sun);
  const SensorAxesEnu a = sensor_axes_enu(mount, stop.theta_R_deg);
  return Vec3{vec3::dot(s, a.x), vec3::dot(s, a.y), vec3::dot(s, a.z)};
}

}  // namespace polrig
