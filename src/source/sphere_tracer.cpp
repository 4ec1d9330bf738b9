#include "polrig/source/sphere_tracer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/random.h"
#include "polrig/vec3.h"
#include "polrig/statistics.h"
#include "polrig/units.h"

namespace polrig {
namespace {

using namespace vec3;

// A direction drawn from the cosine-weighted hemisphere around unit normal n (Malley's method).
Vec3 cosine_direction(const Vec3& n, double u1, double u2) {
  Vec3 t, b;
  basis_around(n, t, b);
  const double r = std::sqrt(u1), phi = 2 * kPi * u2;
  // Renormalised: rounding in |d| would otherwise compound from bounce to bounce.
  return unit(add(add(mul(t, r * std::cos(phi)), mul(b, r * std::sin(phi))),
                        mul(n, std::sqrt(std::max(0.0, 1 - u1)))));
}
Vec3 uniform_direction(double u1, double u2) {
  const double z = 1 - 2 * u1, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPi * u2;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Far root of |o + t·d| = R: the exit through the sphere seen from inside (robust for origins on
// or near the wall, where the near root is ~0). d need not be of unit length.
double sphere_far_root(const Vec3& o, const Vec3& d, double R) {
  const double a = dot(d, d), b = dot(o, d), c = dot(o, o) - R * R;
  const double disc = b * b - a * c;
  if (disc < 0) return -1;
  return (-b + std::sqrt(disc)) / a;
}
double sphere_near_root(const Vec3& o, const Vec3& d, const Vec3& centre, double r) {
  const Vec3 oc = sub(o, centre);
  const double a = dot(d, d), b = dot(oc, d), c = dot(oc, oc) - r * r;
  const double disc = b * b - a * c;
  if (disc < 0) return -1;
  return (-b - std::sqrt(disc)) / a;
}

}  // namespace

struct SphereTracer::Impl {
  struct GeomData {
    Impl* impl;
    unsigned geom;
  };
  std::mutex embree_error_mutex;
  std::string embree_error;  // the first error Embree reported, empty if none
  void throw_on_embree_error() {
    const std::lock_guard lock(embree_error_mutex);
    if (!embree_error.empty()) throw std::runtime_error("Embree: " + embree_error);
  }
  std::vector<GeomData> geom_data;  // user data of the Embree geometries; reserved, never moves
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  // Released here, not in ~SphereTracer, so that a constructor that throws halfway leaks nothing.
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  const SceneSpec* spec = nullptr;
  double R = 0, port_z = 0;
  std::vector<int> lamp_of_prim;  // lamps with radius > 0
  std::vector<Vec3> baffle_normal;
  unsigned wall_geom = RTC_INVALID_GEOMETRY_ID, lamp_geom = RTC_INVALID_GEOMETRY_ID,
           baffle_geom = RTC_INVALID_GEOMETRY_ID;

  // Exact intersection with one primitive, in double precision; returns t or −1.
  double intersect(unsigned geom, unsigned prim, const Vec3& o, const Vec3& d, double t_min) const {
    if (geom == wall_geom) {
      const double t = sphere_far_root(o, d, R);
      if (t <= t_min) return -1;
      if (o[2] + t * d[2] < port_z) return -1;  // the port: no wall there
      return t;
    }
    if (geom == lamp_geom) {
      const LampSpec& l = spec->lamps[static_cast<std::size_t>(lamp_of_prim[prim])];
      const double t = sphere_near_root(o, d, l.position, l.radius);
      return t > t_min ? t : -1;
    }
    const BaffleSpec& b = spec->baffles[prim];
    const Vec3& n = baffle_normal[prim];
    const double denom = dot(d, n);
    if (denom == 0) return -1;
    const double t = dot(sub(b.centre, o), n) / denom;
    if (t <= t_min) return -1;
    const Vec3 p = sub(add(o, mul(d, t)), b.centre);
    return dot(p, p) <= b.radius * b.radius ? t : -1;
  }

  // The first surface along a ray by trying every primitive with the same exact intersection
  // as Embree's callback: for the few primitives of a scene, cheaper than a traversal. Returns
  // false when the scene has too many primitives for that (the caller then asks Embree).
  struct Nearest {
    unsigned geom = RTC_INVALID_GEOMETRY_ID, prim = 0;
    double t = -1;
  };
  static constexpr std::size_t kExhaustiveLimit = 8;
  bool exhaustive() const { return lamp_of_prim.size() + spec->baffles.size() <= kExhaustiveLimit; }
  Nearest nearest(const Vec3& o, const Vec3& d, double t_min) const {
    Nearest n;
    const auto consider = [&](unsigned geom, unsigned prim) {
      const double t = intersect(geom, prim, o, d, t_min);
      // As the callback: a candidate replaces the hit unless its float t lies beyond it.
      if (t < 0 || (n.t >= 0 && static_cast<float>(t) > static_cast<float>(n.t))) return;
      n = {geom, prim, t};
    };
    consider(wall_geom, 0);
    for (unsigned i = 0; i < lamp_of_prim.size(); ++i) consider(lamp_geom, i);
    for (unsigned i = 0; i < spec->baffles.size(); ++i) consider(baffle_geom, i);
    return n;
  }
};

namespace {

const char* embree_error_text(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
  }
}

void record_embree_error(void* user, RTCError code, const char* message) {
  auto& m = *static_cast<SphereTracer::Impl*>(user);
  const std::lock_guard lock(m.embree_error_mutex);
  if (m.embree_error.empty())
    m.embree_error = fmt::format("{}{}{}", embree_error_text(code), message ? ": " : "", message ? message : "");
}

// Embree callbacks. Rays arrive in single precision; `RayContext` carries the double-precision
// ray so that user geometry can intersect exactly, and the exact t of the hit Embree keeps.
struct RayContext {
  RTCIntersectContext base;
  Vec3 o, d;
  double t_min;
  double t_hit = -1;
};

RayContext ray_context(const Vec3& o, const Vec3& d, double t_min) {
  RayContext ctx;
  rtcInitIntersectContext(&ctx.base);
  ctx.o = o;
  ctx.d = d;
  ctx.t_min = t_min;
  return ctx;
}

RTCRayHit ray_hit(const Vec3& o, const Vec3& d, float tnear) {
  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(o[0]);
  rh.ray.org_y = static_cast<float>(o[1]);
  rh.ray.org_z = static_cast<float>(o[2]);
  rh.ray.dir_x = static_cast<float>(d[0]);
  rh.ray.dir_y = static_cast<float>(d[1]);
  rh.ray.dir_z = static_cast<float>(d[2]);
  rh.ray.tnear = tnear;
  rh.ray.tfar = std::numeric_limits<float>::infinity();
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.flags = 0;
  rh.ray.time = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

void bounds_cb(const RTCBoundsFunctionArguments* args) {
  const auto* g = static_cast<const SphereTracer::Impl::GeomData*>(args->geometryUserPtr);
  const SphereTracer::Impl& m = *g->impl;
  RTCBounds* b = args->bounds_o;
  Vec3 lo, hi;
  if (g->geom == m.wall_geom) {
    lo = {-m.R, -m.R, -m.R};
    hi = {m.R, m.R, m.R};
  } else if (g->geom == m.lamp_geom) {
    const LampSpec& l = m.spec->lamps[static_cast<std::size_t>(m.lamp_of_prim[args->primID])];
    lo = sub(l.position, {l.radius, l.radius, l.radius});
    hi = add(l.position, {l.radius, l.radius, l.radius});
  } else {
    const BaffleSpec& s = m.spec->baffles[args->primID];
    lo = sub(s.centre, {s.radius, s.radius, s.radius});
    hi = add(s.centre, {s.radius, s.radius, s.radius});
  }
  const float pad = 1e-3f;
  b->lower_x = static_cast<float>(lo[0]) - pad;
  b->lower_y = static_cast<float>(lo[1]) - pad;
  b->lower_z = static_cast<float>(lo[2]) - pad;
  b->upper_x = static_cast<float>(hi[0]) + pad;
  b->upper_y = static_cast<float>(hi[1]) + pad;
  b->upper_z = static_cast<float>(hi[2]) + pad;
}

void intersect_cb(const RTCIntersectFunctionNArguments* args) {
  if (args->N != 1 || !args->valid[0]) return;
  const auto* g = static_cast<const SphereTracer::Impl::GeomData*>(args->geometryUserPtr);
  RayContext* ctx = reinterpret_cast<RayContext*>(args->context);
  RTCRayHit* rh = reinterpret_cast<RTCRayHit*>(args->rayhit);
  const double t = g->impl->intersect(g->geom, args->primID, ctx->o, ctx->d, ctx->t_min);
  if (t < 0 || static_cast<float>(t) > rh->ray.tfar) return;
  rh->ray.tfar = static_cast<float>(t);
  ctx->t_hit = t;
  rh->hit.geomID = args->geomID;
  rh->hit.primID = args->primID;
  rh->hit.u = rh->hit.v = 0;
  rh->hit.Ng_x = rh->hit.Ng_y = rh->hit.Ng_z = 0;
}

unsigned add_user_geometry(SphereTracer::Impl& m, unsigned prims,
                           std::vector<SphereTracer::Impl::GeomData>& data) {
  RTCGeometry geom = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geom, prims);
  const unsigned id = rtcAttachGeometry(m.scene, geom);
  data.push_back({&m, id});
  rtcSetGeometryUserData(geom, &data.back());
  rtcSetGeometryBoundsFunction(geom, bounds_cb, nullptr);
  rtcSetGeometryIntersectFunction(geom, intersect_cb);
  rtcCommitGeometry(geom);
  rtcReleaseGeometry(geom);
  return id;
}

}  // namespace

SphereTracer::SphereTracer(const SceneSpec& scene) : scene_(scene), impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.spec = &scene_;
  m.R = scene_.sphere.radius();
  m.port_z = scene_.port_plane_z();
  // No "threads=N" config: Embree would cap the process-wide TBB parallelism with it.
  m.device = rtcNewDevice(nullptr);
  if (!m.device)
    throw std::runtime_error(fmt::format("Embree: cannot create a device ({})",
                                         embree_error_text(rtcGetDeviceError(nullptr))));
  // Embree reports errors through this callback (and otherwise only through polling); they are
  // kept and turned into an exception after each step that builds the scene.
  rtcSetDeviceErrorFunction(m.device, record_embree_error, &m);
  m.scene = rtcNewScene(m.device);
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
  m.geom_data.reserve(3);
  m.wall_geom = add_user_geometry(m, 1, m.geom_data);
  for (std::size_t i = 0; i < scene_.lamps.size(); ++i)
    if (scene_.lamps[i].radius > 0) m.lamp_of_prim.push_back(static_cast<int>(i));
  if (!m.lamp_of_prim.empty())
    m.lamp_geom = add_user_geometry(m, static_cast<unsigned>(m.lamp_of_prim.size()), m.geom_data);
  for (const BaffleSpec& b : scene_.baffles) {
    m.baffle_normal.push_back(unit(b.normal));
    const Vec3& n = m.baffle_normal.back();
    if (!(std::abs(dot(n, n) - 1) < 1e-9))  // a zero, or a length whose square over/underflows
      throw std::invalid_argument(fmt::format("baffle normal [{}, {}, {}] has no direction the "
                                              "tracer can represent", b.normal[0], b.normal[1],
                                              b.normal[2]));
  }
  if (!scene_.baffles.empty())
    m.baffle_geom = add_user_geometry(m, static_cast<unsigned>(scene_.baffles.size()), m.geom_data);
  rtcCommitScene(m.scene);
  m.throw_on_embree_error();
}

SphereTracer::~SphereTracer() = default;

namespace {
void require_finite_ray(const Vec3& o, const Vec3& d) {
  if (!(std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2]) && std::isfinite(d[0]) &&
        std::isfinite(d[1]) && std::isfinite(d[2])))
    throw std::logic_error(fmt::format("non-finite ray ({}, {}, {}) + t({}, {}, {})", o[0], o[1], o[2], d[0], d[1], d[2]));
}
}  // namespace

SphereTracer::Hit SphereTracer::first_hit(const Vec3& o, const Vec3& d, double t_min) const {
  const Impl& m = *impl_;
  require_finite_ray(o, d);
  RayContext ctx = ray_context(o, d, t_min);
  RTCRayHit rh = ray_hit(o, d, 0.0f);
  rtcIntersect1(m.scene, &ctx.base, &rh);
  Hit h;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
  // The float tfar ordered the candidates; the point comes from the exact double root.
  const double t = ctx.t_hit;
  h.t = t;
  h.point = add(o, mul(d, t));
  if (rh.hit.geomID == m.wall_geom) {
    h.kind = Hit::Wall;
  } else if (rh.hit.geomID == m.lamp_geom) {
    h.kind = Hit::Lamp;
    h.index = m.lamp_of_prim[rh.hit.primID];
  } else {
    h.kind = Hit::Baffle;
    h.index = static_cast<int>(rh.hit.primID);
    h.front = dot(d, m.baffle_normal[rh.hit.primID]) < 0;
  }
  return h;
}

namespace {

// atan2(y, x) to within 2e-6 rad (a minimax polynomial for atan on [0, 1]), for x, y not both 0.
double coarse_atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double r = std::min(ax, ay) / std::max(ax, ay), r2 = r * r;
  double a = r * (0.99997726 + r2 * (-0.33262347 + r2 * (0.19354346 + r2 * (-0.11643287 + r2 * (0.05265332 - r2 * 0.01172120)))));
  if (ay > ax) a = 0.5 * kPi - a;
  if (x < 0) a = kPi - a;
  return y < 0 ? -a : a;
}

// The azimuth bin of (x, y) among n equal bins from φ = 0: floor(atan2(y, x)/(2π)·n), with φ
// taken in [0, 2π). The coarse atan2 decides it away from the bins' edges, where its error
// cannot move the floor; near an edge (or at the pole) the exact atan2 does, so the bin is
// always the exact one.
int azimuth_bin(double y, double x, int n) {
  constexpr double kCoarseError = 1e-4;  // rad: 50 times the polynomial's
  if (x != 0 || y != 0) {
    double phi = coarse_atan2(y, x);
    if (phi < 0) phi += 2 * kPi;
    const double t = phi / (2 * kPi) * n, f = t - std::floor(t), edge = kCoarseError / (2 * kPi) * n;
    if (f > edge && f < 1 - edge) return std::clamp(static_cast<int>(t), 0, n - 1);
  }
  double phi = std::atan2(y, x);
  if (phi < 0) phi += 2 * kPi;
  return std::clamp(static_cast<int>(phi / (2 * kPi) * n), 0, n - 1);
}

// Equal-area wall bin of a point on the sphere.
int wall_bin(const WallMap& w, const Vec3& p, double R) {
  const double c = std::clamp(p[2] / R, -1.0, 1.0);
  int it = static_cast<int>((1.0 - c) * 0.5 * w.n_theta);
  it = std::clamp(it, 0, w.n_theta - 1);
  return w.bin(it, azimuth_bin(p[1], p[0], w.n_phi));
}

struct BatchTally {
  std::vector<double> wall_W, wall_first_W;  // power landing on each bin
  std::vector<std::array<double, 2>> baffle_W;
  EnergyLedger ledger;
};

}  // namespace

SphereSolution SphereTracer::trace_photons(const Progress& progress) const {
  const Impl& m = *impl_;
  const TraceSettings& ts = scene_.trace;
  const auto t0 = std::chrono::steady_clock::now();

  SphereSolution sol;
  WallMap& w = sol.wall;
  w.n_theta = ts.wall_bins_theta;
  w.n_phi = ts.wall_bins_phi;
  const std::size_t bins = static_cast<std::size_t>(w.n_theta) * static_cast<std::size_t>(w.n_phi);
  // Wall area of each bin: the band between cos θ_k and cos θ_k+1, less the port cap below
  // port_z, split over φ.
  w.wall_area_mm2.assign(bins, 0.0);
  for (int it = 0; it < w.n_theta; ++it) {
    const double c_hi = 1.0 - 2.0 * it / w.n_theta, c_lo = 1.0 - 2.0 * (it + 1) / w.n_theta;
    const double c_cut = m.port_z / m.R;
    const double band = std::max(0.0, c_hi - std::max(c_lo, c_cut));
    for (int ip = 0; ip < w.n_phi; ++ip) w.wall_area_mm2[static_cast<std::size_t>(w.bin(it, ip))] = 2 * kPi * m.R * m.R * band / w.n_phi;
  }

  std::vector<double> lamp_cdf;
  for (const LampSpec& l : scene_.lamps) {
    sol.power_W += l.power;
    lamp_cdf.push_back(sol.power_W);
  }
  const int B = ts.batches;
  const long long per_batch = ts.photons / B;
  const double photon_W = sol.power_W / static_cast<double>(per_batch * B);

  std::vector<BatchTally> tally(static_cast<std::size_t>(B));
  progress.begin("sphere solve: photons", per_batch * B);
  constexpr long long kReportEvery = 4096;
  tbb::parallel_for(0, B, [&](int b) {
    BatchTally& t = tally[static_cast<std::size_t>(b)];
    t.wall_W.assign(bins, 0.0);
    t.wall_first_W.assign(bins, 0.0);
    t.baffle_W.assign(scene_.baffles.size(), {0.0, 0.0});
    for (long long k = 0; k < per_batch; ++k) {
      const std::uint64_t photon = static_cast<std::uint64_t>(b) * static_cast<std::uint64_t>(per_batch) + static_cast<std::uint64_t>(k);
      std::uint64_t draw = 0;
      const UniformStream stream(ts.seed, photon, 0x5AB1);
      const auto u = [&]() { return stream(draw++); };
      ++t.ledger.launched;
      if ((k + 1) % kReportEvery == 0) progress.advance(kReportEvery);
      // Emission: a lamp by power, a point on its surface, a cosine-weighted direction.
      const double pick = u() * sol.power_W;
      const std::size_t li = static_cast<std::size_t>(std::lower_bound(lamp_cdf.begin(), lamp_cdf.end(), pick) - lamp_cdf.begin());
      const LampSpec& lamp = scene_.lamps[std::min(li, scene_.lamps.size() - 1)];
      Vec3 o, d;
      if (lamp.radius > 0) {
        const Vec3 n = uniform_direction(u(), u());
        o = add(lamp.position, mul(n, lamp.radius));
        d = cosine_direction(n, u(), u());
      } else {
        o = lamp.position;
        d = uniform_direction(u(), u());
      }
      bool first = true;
      for (;;) {
        ++t.ledger.rays;
        const Hit h = first_hit(o, d);
        if (h.kind == Hit::None) {
          // No surface: the ray left through the port, or the geometry leaked it.
          const double tf = sphere_far_root(o, d, m.R);
          if (tf > 0 && o[2] + tf * d[2] < m.port_z) ++t.ledger.escaped;
          else ++t.ledger.leaked;
          break;
        }
        if (h.kind == Hit::Wall) {
          const int bin = wall_bin(w, h.point, m.R);
          t.wall_W[static_cast<std::size_t>(bin)] += photon_W;
          if (first) t.wall_first_W[static_cast<std::size_t>(bin)] += photon_W;
          first = false;
          if (u() >= scene_.sphere.reflectance) {
            ++t.ledger.absorbed_wall;
            break;
          }
          o = h.point;
          d = cosine_direction(mul(unit(h.point), -1.0), u(), u());
          continue;
        }
        first = false;
        if (h.kind == Hit::Lamp) {
          const LampSpec& l = scene_.lamps[static_cast<std::size_t>(h.index)];
          if (u() >= l.reflectance) {
            ++t.ledger.absorbed_lamps;
            break;
          }
          o = h.point;
          d = cosine_direction(unit(sub(h.point, l.position)), u(), u());
          continue;
        }
        const BaffleSpec& bf = scene_.baffles[static_cast<std::size_t>(h.index)];
        t.baffle_W[static_cast<std::size_t>(h.index)][h.front ? 0 : 1] += photon_W;
        if (u() >= bf.reflectance) {
          ++t.ledger.absorbed_baffles;
          break;
        }
        const Vec3 n = mul(m.baffle_normal[static_cast<std::size_t>(h.index)], h.front ? 1.0 : -1.0);
        o = h.point;
        d = cosine_direction(n, u(), u());
      }
    }
    progress.advance(per_batch % kReportEvery);
  });
  progress.finish();

  // Combine batches in order: means and standard errors of the per-batch estimates.
  const auto combine = [&](auto get, std::size_t n, double area_of(std::size_t, const WallMap&, const SceneSpec&),
                           std::vector<double>& mean, std::vector<double>& se) {
    mean.assign(n, 0.0);
    se.assign(n, 0.0);
    std::vector<double> per_batch(static_cast<std::size_t>(B));
    for (std::size_t i = 0; i < n; ++i) {
      const double area_m2 = area_of(i, w, scene_) * 1e-6;
      for (int b = 0; b < B; ++b)  // each batch's estimate as if it were the whole run
        per_batch[static_cast<std::size_t>(b)] =
            area_m2 > 0 ? get(tally[static_cast<std::size_t>(b)], i) * B / area_m2 : 0.0;
      const MeanAndSpread m = mean_and_standard_error(per_batch);
      mean[i] = m.mean;
      se[i] = m.sd;
    }
  };
  const auto wall_area = [](std::size_t i, const WallMap& wm, const SceneSpec&) { return wm.wall_area_mm2[i]; };
  combine([](const BatchTally& t, std::size_t i) { return t.wall_W[i]; }, bins, wall_area, w.E, w.E_se);
  combine([](const BatchTally& t, std::size_t i) { return t.wall_first_W[i]; }, bins, wall_area, w.E_first, w.E_first_se);
  sol.baffle_E.assign(scene_.baffles.size(), {0.0, 0.0});
  for (std::size_t i = 0; i < scene_.baffles.size(); ++i) {
    const double area_m2 = kPi * scene_.baffles[i].radius * scene_.baffles[i].radius * 1e-6;
    for (const BatchTally& t : tally)
      for (int f = 0; f < 2; ++f) sol.baffle_E[i][static_cast<std::size_t>(f)] += t.baffle_W[i][static_cast<std::size_t>(f)] / area_m2;
  }
  for (const BatchTally& t : tally) {
    double indirect = 0;
    for (std::size_t i = 0; i < bins; ++i) indirect += t.wall_W[i] - t.wall_first_W[i];
    sol.batch_indirect_W.push_back(indirect * B);  // as if the batch were the whole run
    EnergyLedger& L = sol.ledger;
    L.launched += t.ledger.launched;
    L.absorbed_wall += t.ledger.absorbed_wall;
    L.absorbed_baffles += t.ledger.absorbed_baffles;
    L.absorbed_lamps += t.ledger.absorbed_lamps;
    L.escaped += t.ledger.escaped;
    L.leaked += t.ledger.leaked;
    L.rays += t.ledger.rays;
  }
  sol.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

SphereSolution SphereTracer::solve(const Progress& progress) const {
  const auto t0 = std::chrono::steady_clock::now();
  SphereSolution sol = trace_photons(progress);
  impl_->throw_on_embree_error();
  const int steps = static_cast<int>(std::lround(180.0 / scene_.trace.field_step_deg));
  sol.field = compute_wall_field(*this, sol, steps + 1, 2 * steps, progress);
  sol.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

double SphereTracer::radiance(const SphereSolution& s, const Hit& h) const {
  switch (h.kind) {
    case Hit::Wall: {
      // The computed field when there is one (a solve), else the bin (maps made by hand in tests).
      if (!s.field.empty())
        return scene_.sphere.reflectance * (direct_irradiance(h.point) + s.field.after_first_strike(h.point)) / kPi;
      return scene_.sphere.reflectance * s.wall.E[static_cast<std::size_t>(wall_bin(s.wall, h.point, impl_->R))] / kPi;
    }
    case Hit::Baffle: {
      const BaffleSpec& b = scene_.baffles[static_cast<std::size_t>(h.index)];
      return b.reflectance * s.baffle_E[static_cast<std::size_t>(h.index)][h.front ? 0 : 1] / kPi;
    }
    case Hit::Lamp: {
      const LampSpec& l = scene_.lamps[static_cast<std::size_t>(h.index)];
      return l.power / (kPi * 4 * kPi * l.radius * l.radius * 1e-6);
    }
    case Hit::None: break;
  }
  return 0.0;
}

double SphereTracer::direct_irradiance(const Vec3& wall_point) const {
  // A uniformly emitting Lambertian sphere radiates like a point of intensity Φ/(4π) at its
  // centre (outside it); the wall point sees it when the line to the centre is free.
  const Vec3 n = mul(unit(wall_point), -1.0);  // inward normal
  double e = 0;
  for (std::size_t i = 0; i < scene_.lamps.size(); ++i) {
    const LampSpec& l = scene_.lamps[i];
    const Vec3 to = sub(l.position, wall_point);
    const double D2 = dot(to, to), D = std::sqrt(D2);
    const Vec3 dir = mul(to, 1.0 / D);
    const double cos_w = dot(n, dir);
    if (cos_w <= 0) continue;
    bool seen = false;
    if (impl_->exhaustive()) {
      require_finite_ray(wall_point, dir);
      const Impl::Nearest h = impl_->nearest(wall_point, dir, 1e-9);
      seen = l.radius > 0 ? (h.geom == impl_->lamp_geom && impl_->lamp_of_prim[h.prim] == static_cast<int>(i))
                          : (h.t < 0 || h.t >= D);
    } else {
      const Hit h = first_hit(wall_point, dir, 1e-9);
      seen = l.radius > 0 ? (h.kind == Hit::Lamp && h.index == static_cast<int>(i))
                          : (h.kind == Hit::None || h.t >= D);
    }
    if (!seen) continue;
    e += l.power / (4 * kPi) * cos_w / D2 * 1e6;  // W/m²
  }
  return e;
}

std::vector<SphereTracer::Ray> SphereTracer::wall_rays(long long count, std::uint64_t seed) const {
  std::vector<Ray> rays;
  rays.reserve(static_cast<std::size_t>(count));
  for (long long k = 0; k < count; ++k) {
    const auto u = [&](std::uint64_t j) { return uniform_unit(seed, static_cast<std::uint64_t>(k), 0xBE, j); };
    const Vec3 n = uniform_direction(u(0), u(1));
    rays.push_back({mul(n, impl_->R), cosine_direction(mul(n, -1.0), u(2), u(3))});
  }
  return rays;
}

long long SphereTracer::plain_intersections(const std::vector<Ray>& rays) const {
  const Impl& m = *impl_;
  long long hits = 0;
  for (const Ray& r : rays) {
    // The user geometry reads the double-precision ray from the context.
    RayContext rc = ray_context(r.origin, r.dir, 1e-9);
    RTCRayHit rh = ray_hit(r.origin, r.dir, 1e-4f);
    rtcIntersect1(m.scene, &rc.base, &rh);
    hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }
  return hits;
}

}  // namespace polrig
