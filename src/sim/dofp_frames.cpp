#include "polrig/sim/dofp_frames.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "polrig/random.h"
#include "polrig/units.h"
#include "polrig/vector_log.h"

namespace polrig {

std::vector<DofpStop> dofp_stops(const Schedule& schedule) {
  std::vector<DofpStop> stops;
  const int frames = schedule.frames_per_stop;
  for (double level : schedule.unpolarized_levels)
    stops.push_back({0, false, level, schedule.start_deg, 0.0, frames});
  const std::vector<double> angles = schedule.table_angles_deg();
  for (double intensity : schedule.intensities)
    for (double a : angles) stops.push_back({0, true, intensity, a, 0.0, frames});
  for (std::size_t k = 0; k < stops.size(); ++k) {
    stops[k].index = static_cast<int>(k);
    if (k > 0)
      stops[k].t_s = stops[k - 1].t_s + std::abs(stops[k].theta_R_deg - stops[k - 1].theta_R_deg) / schedule.speed_deg_s +
                     schedule.dwell_s;
  }
  return stops;
}

void check_camera_light(const Rig& rig) {
  if (!rig.light || !rig.light->has(Source::kStokesAlongViews))
    throw std::invalid_argument(fmt::format(
        "source.model {} gives no light along a camera's views (it lacks kStokesAlongViews)",
        rig.source.model));
  if (rig_sky(rig) && !rig.schedule.unpolarized_levels.empty())
    throw std::invalid_argument(
        "schedule.unpolarized_levels: the sky cannot be unpolarized (expected no unpolarized levels under the sky)");
}

DofpSimulator::DofpSimulator(const Rig& rig, DofpAnalyzer analyzer) : rig_(rig), analyzer_(analyzer) {
  if (!rig.instrument().has(Instrument::kMosaic))
    throw std::invalid_argument(fmt::format("device.kind {} has no polarizer mosaic (expected dofp-camera)",
                                            rig.device_kind));
  check_camera_light(rig);
  if (rig.schedule.frames_per_stop < 1)
    throw std::invalid_argument(fmt::format("schedule.frames_per_stop = {} (expected ≥ 1)", rig.schedule.frames_per_stop));
  truth_ = make_dofp_truth(rig.camera, derive_seed(rig.seed, 1));
  noise_seed_ = derive_seed(rig.seed, 2);
  stops_ = dofp_stops(rig.schedule);
  const int W = truth_.width, H = truth_.height;
  const std::size_t n = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  pixels_.resize(n);
  // pixel_view's a = (col + ½ − W/2, row + ½ − H/2, f_c), by column, by row and per pixel 1/|a|.
  const DofpCameraSpec& spec = rig.camera;
  view_x_.resize(static_cast<std::size_t>(W));
  view_y_.resize(static_cast<std::size_t>(H));
  for (int col = 0; col < W; ++col) view_x_[static_cast<std::size_t>(col)] = col + 0.5 - 0.5 * spec.width_px;
  for (int row = 0; row < H; ++row) view_y_[static_cast<std::size_t>(row)] = row + 0.5 - 0.5 * spec.height_px;
  view_f_ = focal_px(spec);
  for (int row = 0; row < H; ++row)
    for (int col = 0; col < W; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * static_cast<std::size_t>(W) + static_cast<std::size_t>(col);
      const Vec3 a{view_x_[static_cast<std::size_t>(col)], view_y_[static_cast<std::size_t>(row)], view_f_};
      const double inv = 1.0 / vec3::norm(a);
      const Vec3 v = pixel_view(spec, col, row);
      if (vec3::mul(a, inv) != v)
        throw std::logic_error(fmt::format("DofpSimulator: pixel ({}, {})'s view is not pixel_view's a/|a| "
                                           "(the simulator's view factors must follow pixel_view)", col, row));
      const double beta = 2.0 * deg2rad(truth_.alpha_deg[i] - truth_.eps_deg[i]);
      const double A = 0.5 * truth_.K[i], Ak = A * truth_.k[i];
      pixels_[i] = {inv, A, Ak * std::cos(beta), Ak * std::sin(beta)};
    }
}

std::vector<std::uint16_t> DofpSimulator::frame(const DofpStop& stop, int frame, DofpTruthLayers* layers) const {
  // frame(signal(stop, layers), frame) without keeping f: each row exposed as it is made.
  std::vector<std::uint16_t> raw(truth_.b.size());
  const DofpExposure expose(rig_.camera, noise_seed_, static_cast<std::uint64_t>(stop.index),
                            static_cast<std::uint64_t>(frame));
  const double* b = truth_.b.data();
  signal_rows(stop, layers, [&](std::size_t first, std::span<const double> f) {
    for (std::size_t c = 0; c < f.size(); ++c) raw[first + c] = expose(f[c], b[first + c], first + c);
  });
  return raw;
}

std::vector<std::uint16_t> DofpSimulator::frame(const StopSignal& signal, int frame) const {
  const std::size_t n = signal.f.size();
  std::vector<std::uint16_t> raw(n);
  const DofpExposure expose(rig_.camera, noise_seed_, static_cast<std::uint64_t>(signal.stop.index),
                            static_cast<std::uint64_t>(frame));
  const double* f = signal.f.data();
  const double* b = truth_.b.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) raw[i] = expose(f[i], b[i], i);
  });
  return raw;
}

DofpSimulator::StopSignal DofpSimulator::signal(const DofpStop& stop, DofpTruthLayers* layers) const {
  StopSignal out{stop, std::vector<double>(truth_.b.size())};
  signal_rows(stop, layers, [&](std::size_t first, std::span<const double> f) {
    std::copy(f.begin(), f.end(), out.f.begin() + static_cast<std::ptrdiff_t>(first));
  });
  return out;
}

namespace {
// One row's work before and after the light along its views, in loops without branches over plain
// arrays (the compiler vectorises them), compiled once per instruction set: the same operations in
// the same order in each (no contraction: this file is compiled with -ffp-contract=off and AVX2
// without FMA), so the same bits from both.
template <class Px>
inline __attribute__((always_inline)) void views_row(const double* xs, double y, double fc, const Px* px,
                                                     const InstrumentAxes& A, Vec3* views, std::size_t n) {
  for (std::size_t c = 0; c < n; ++c) {
    const double inv = px[c].inv;
    const double vx = xs[c] * inv, vy = y * inv, vz = fc * inv;  // pixel_view: a·(1/|a|)
    views[c] = {vx * A.x[0] + vy * A.y[0] + vz * A.z[0], vx * A.x[1] + vy * A.y[1] + vz * A.z[1],
                vx * A.x[2] + vy * A.y[2] + vz * A.z[2]};
  }
}
template <class Px>
__attribute__((target("avx2"))) void views_row_avx2(const double* xs, double y, double fc, const Px* px,
                                                     const InstrumentAxes& A, Vec3* views, std::size_t n) {
  views_row(xs, y, fc, px, A, views, n);
}
template <class Px>
void views_row_baseline(const double* xs, double y, double fc, const Px* px, const InstrumentAxes& A, Vec3* views,
                        std::size_t n) {
  views_row(xs, y, fc, px, A, views, n);
}

struct RowOut {
  double *u, *w, *c2, *s2, *I, *d, *f;
};
template <bool image_plane, class Px>
inline __attribute__((always_inline)) void signal_row(const double* xs, double y, double fc, const Px* px,
                                                      const double* b, const InstrumentAxes& A,
                                                      const ViewLight* lights, std::size_t n, bool vignetting,
                                                      double intensity, bool polarized, const RowOut& o) {
  double *u = o.u, *w = o.w, *c2 = o.c2, *s2 = o.s2, *I = o.I, *d = o.d, *fw = o.f;
  for (std::size_t c = 0; c < n; ++c) {
    const double inv = px[c].inv;
    const double vx = xs[c] * inv, vy = y * inv, vz = fc * inv;
    const ViewLight& L = lights[c];
    const double e0 = vec3::dot(L.e, A.x), e1 = vec3::dot(L.e, A.y), e2 = vec3::dot(L.e, A.z);  // frame l
    if constexpr (image_plane) {
      // Frame i's axes turned by α, P = cos α·X_i − sin α·Y_i and Q = sin α·X_i + cos α·Y_i, are
      // the rotation taking ẑ to v applied to x̂ and ŷ: with g = 1/(1 + v_z),
      // P = (1 − g·v_x², −g·v_x·v_y, −v_x), Q = (−g·v_x·v_y, 1 − g·v_y², −v_y); φ_pix = atan2(e·Q, e·P).
      const double g = 1.0 / (1.0 + vz);
      const double gxy = g * vx * vy;
      u[c] = e0 * (1.0 - g * vx * vx) - e1 * gxy - e2 * vx;
      w[c] = -e0 * gxy + e1 * (1.0 - g * vy * vy) - e2 * vy;
    } else {
      // m = v × e; the axis in the image is ⊥ (m_x, m_y): u = −m_y, w = m_x.
      u[c] = -(vz * e0 - vx * e2);
      w[c] = vy * e2 - vz * e1;
    }
    const double Ic = L.S0 * intensity;
    I[c] = vignetting ? Ic * ((vz * vz) * (vz * vz)) : Ic;  // cos⁴γ
    d[c] = polarized ? L.d : 0.0;
  }
  for (std::size_t c = 0; c < n; ++c) {
    const double n2 = u[c] * u[c] + w[c] * w[c];
    const bool some = n2 > 0;
    const double r = 1.0 / (some ? n2 : 1.0);
    c2[c] = some ? (u[c] * u[c] - w[c] * w[c]) * r : 1.0;
    s2[c] = some ? 2.0 * u[c] * w[c] * r : 0.0;
    const Px& p = px[c];
    fw[c] = I[c] * (p.A + d[c] * (c2[c] * p.B + s2[c] * p.C)) + b[c];
  }
}
#define POLRIG_SIGNAL_ROW_ARGS                                                                                \
  const double *xs, double y, double fc, const Px *px, const double *b, const InstrumentAxes &A,             \
      const ViewLight *lights, std::size_t n, bool image_plane, bool vignetting, double intensity, bool polarized, \
      const RowOut &o
#define POLRIG_SIGNAL_ROW_CALL                                                                              \
  image_plane ? signal_row<true>(xs, y, fc, px, b, A, lights, n, vignetting, intensity, polarized, o)      \
              : signal_row<false>(xs, y, fc, px, b, A, lights, n, vignetting, intensity, polarized, o)
template <class Px>
__attribute__((target("avx2"))) void signal_row_avx2(POLRIG_SIGNAL_ROW_ARGS) {
  POLRIG_SIGNAL_ROW_CALL;
}
template <class Px>
void signal_row_baseline(POLRIG_SIGNAL_ROW_ARGS) {
  POLRIG_SIGNAL_ROW_CALL;
}
#undef POLRIG_SIGNAL_ROW_ARGS
#undef POLRIG_SIGNAL_ROW_CALL
}  // namespace

void DofpSimulator::signal_rows(const DofpStop& stop, DofpTruthLayers* layers,
                                const std::function<void(std::size_t, std::span<const double>)>& row_done) const {
  const int W = truth_.width, H = truth_.height;
  const std::size_t n = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  const std::unique_ptr<const LightAlongViews> light =
      rig_.light->light_along_views(rig_.source_view(), {stop.theta_R_deg, stop.t_s});
  const InstrumentAxes& A = light->axes;
  if (layers) {
    for (auto* v : {&layers->S0, &layers->S1, &layers->S2, &layers->AoP, &layers->DoP}) v->assign(n, 0.0f);
  }
  const DofpCameraSpec& spec = rig_.camera;
  const bool image_plane = analyzer_ == DofpAnalyzer::ImagePlane, vignetting = spec.vignetting;
  const double intensity = stop.intensity;
  const bool polarized = stop.polarized;
  const bool avx2 = avx2_paths();
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
    // Per row, loops without branches over plain arrays (the compiler vectorises them); the
    // analyzer's choice and the truth layers outside them.
    const std::size_t w_px = static_cast<std::size_t>(W);
    // Work space not zeroed (every entry is written before it is read): zeroing it cost 6 % of a frame.
    const std::unique_ptr<Vec3[]> view_buf = std::make_unique_for_overwrite<Vec3[]>(w_px);
    const std::unique_ptr<double[]> buf = std::make_unique_for_overwrite<double[]>(7 * w_px);
    const std::span<Vec3> views(view_buf.get(), w_px);
    std::vector<ViewLight> lights(w_px);
    double *u = buf.get(), *w = u + w_px, *c2 = w + w_px, *s2 = c2 + w_px, *I = s2 + w_px, *d = I + w_px;
    const std::span<const double> f(d + w_px, w_px);
    double* fw = d + w_px;
    const double* xs = view_x_.data();
    const double fc = view_f_;
    for (int row = rows.begin(); row < rows.end(); ++row) {
      const std::size_t first = static_cast<std::size_t>(row) * w_px;
      const PixelConstants* px = pixels_.data() + first;
      const double* b = truth_.b.data() + first;
      const double y = view_y_[static_cast<std::size_t>(row)];
      (avx2 ? views_row_avx2<PixelConstants> : views_row_baseline<PixelConstants>)(xs, y, fc, px, A, views.data(),
                                                                                   w_px);
      light->along(views, lights);
      const RowOut o{u, w, c2, s2, I, d, fw};
      (avx2 ? signal_row_avx2<PixelConstants> : signal_row_baseline<PixelConstants>)(
          xs, y, fc, px, b, A, lights.data(), w_px, image_plane, vignetting, intensity, polarized, o);
      row_done(first, f);
      if (layers)
        for (std::size_t c = 0; c < w_px; ++c) {
          const std::size_t i = first + c;
          layers->S0[i] = static_cast<float>(I[c]);
          layers->S1[i] = static_cast<float>(I[c] * d[c] * c2[c]);
          layers->S2[i] = static_cast<float>(I[c] * d[c] * s2[c]);
          double aop = rad2deg(0.5 * std::atan2(s2[c], c2[c]));
          if (aop < 0) aop += 180.0;
          layers->AoP[i] = static_cast<float>(aop);
          layers->DoP[i] = static_cast<float>(d[c]);
        }
    }
  });
}

std::optional<double> dofp_true_heading_deg(const Rig& rig, const DofpStop& stop) {
  if (!rig_sky(rig)) return std::nullopt;
  const SensorAxesEnu a = sensor_axes_enu(rig.source.sky.resolved_mount(), stop.theta_R_deg);
  double h = rad2deg(std::atan2(a.x[0], a.x[1]));
  if (h < 0) h += 360.0;
  if (h >= 360.0) h -= 360.0;
  return h;
}

}  // namespace polrig
