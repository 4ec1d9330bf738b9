// FourCameraFusion::fuse's kernel (four_camera_lanes.h): per chunk of kFusionChunk virtual pixels,
// (1) the four bilinear samples F_j = (f_j − b_j)·(1/K_j) (16-bit frames: the taps gathered in
// lanes; a double signal: pixel by pixel), then (2) in float SIMD lanes Eq. 4 with the chunk's W,
// x_r = Σ_{j<4} W_rj·(F_j − F_4) (+ F_4 for S0), and Eq. 5: AoP = ½·atan2(S2, S1) by an atan2 on
// Highway's float arctangent polynomial, DoP = √(S1² + S2²)/S0.
//
// Highway (libhwy-dev) with run-time dispatch, as src/vector_log.cpp and for the same reason: the
// fused layers must not depend on the CPU, so every compiled path does the same IEEE operations
// lane by lane — no fused multiply-add (HWY_DISABLE_BMI2_FMA; this file is compiled with
// -ffp-contract=off; the AVX-512 targets, whose MulAdd is always fused, are not compiled), whole
// vectors only (kFusionChunk is a multiple of every target's lane count). The settings must equal
// vector_log.cpp's (both instantiate Highway's inline functions per target).
// tests/test_four_camera.cpp checks the baseline and the best path give the same bits.
#include "four_camera_lanes.h"

#include <bit>
#include <cstring>
#include <type_traits>

#include "polrig/vector_log.h"

#ifndef HWY_DISABLE_BMI2_FMA
#define HWY_DISABLE_BMI2_FMA
#endif
#undef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_AVX3 | HWY_AVX3_DL)

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "device/four_camera_lanes.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace polrig {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
using detail::FusionChunk;
using detail::kFusionChunk;
using four_camera_lanes::Constants;
using four_camera_lanes::Layers;

// atan2(y, x)·90/π in [0°, 180°): the AoP of (S1, S2) = (x, y). The arctangent of min/max(|x|, |y|)
// ∈ [0, 1] by Highway's float polynomial (its Atan's, within a few ulp), then the octant.
template <class D, class V>
HWY_INLINE V AopDeg(D d, V y, V x) {
  const V zero = hn::Zero(d);
  const V ax = hn::Abs(x), ay = hn::Abs(y);
  const V big = hn::Max(ax, ay), small = hn::Min(ax, ay);
  const V t = hn::IfThenZeroElse(hn::Eq(big, zero), hn::Div(small, big));  // atan2(0, 0) = 0
  hn::impl::AtanImpl<float> arctan;
  V r = arctan.AtanPoly(d, t);
  r = hn::IfThenElse(hn::Gt(ay, ax), hn::Sub(hn::Set(d, 1.57079632679489661923f), r), r);
  r = hn::IfThenElse(hn::Lt(x, zero), hn::Sub(hn::Set(d, 3.14159265358979323846f), r), r);
  V aop = hn::Mul(hn::CopySign(r, y), hn::Set(d, static_cast<float>(90.0 / 3.14159265358979323846)));
  aop = hn::IfThenElse(hn::Lt(aop, zero), hn::Add(aop, hn::Set(d, 180.0f)), aop);
  return hn::IfThenZeroElse(hn::Ge(aop, hn::Set(d, 180.0f)), aop);
}

// Step (1) for a double signal (the noise-free frames), pixel by pixel: F_j of each pixel, and
// whether all four cameras see it (1 or 0). The bilinear sum in double, then (f − b)·(1/K_j) in
// float, the order of FuseChunksU16's float operations.
template <class T>
HWY_INLINE void Samples(const FusionChunk& c, const T* const frames[kFourCameras], const Constants& k,
                        float (&F)[kFourCameras][kFusionChunk], float (&seen)[kFusionChunk]) {
  using A = std::conditional_t<std::is_same_v<T, double>, double, float>;
  const std::size_t w = k.width;
  for (std::size_t i = 0; i < kFusionChunk; ++i) {
    const bool all = c.index[0][i] >= 0 && c.index[1][i] >= 0 && c.index[2][i] >= 0 && c.index[3][i] >= 0;
    seen[i] = all ? 1.0f : 0.0f;
    for (std::size_t j = 0; j < kFourCameras; ++j) {
      if (!all) {
        F[j][i] = 0.0f;
        continue;
      }
      const T* p = frames[j] + c.index[j][i];
      const A wx = c.wx[j][i], wy = c.wy[j][i];
      const A p0 = static_cast<A>(p[0]), p1 = static_cast<A>(p[1]), p2 = static_cast<A>(p[w]),
              p3 = static_cast<A>(p[w + 1]);
      const A top = p0 + wx * (p1 - p0), bottom = p2 + wx * (p3 - p2);
      F[j][i] = (static_cast<float>(top + wy * (bottom - top)) - k.b[j]) * k.inv_K[j];
    }
  }
}

// Step (2) for lanes i … i + N: Eq. 4 with the chunk's W, Eq. 5, the stores.
template <class D, class V, class M>
HWY_INLINE void Fuse(D d, const FusionChunk& c, std::size_t i, const V (&F)[kFourCameras], M seen, const Layers& out,
                     std::size_t o, float* valid) {
  const auto zero = hn::Zero(d);
  const V d1 = hn::Sub(F[0], F[3]), d2 = hn::Sub(F[1], F[3]), d3 = hn::Sub(F[2], F[3]);
  const auto row = [&](int r) {
    return hn::Add(hn::Add(hn::Mul(hn::Load(d, c.W[3 * r] + i), d1), hn::Mul(hn::Load(d, c.W[3 * r + 1] + i), d2)),
                   hn::Mul(hn::Load(d, c.W[3 * r + 2] + i), d3));
  };
  const V S1 = row(0), S2 = row(1), S0 = hn::Add(F[3], row(2));
  const auto ok = hn::And(seen, hn::Gt(S0, zero));
  const V dop = hn::Div(hn::Sqrt(hn::Add(hn::Mul(S1, S1), hn::Mul(S2, S2))), S0);
  hn::StoreU(hn::IfThenElseZero(ok, S0), d, out.S0 + o + i);
  hn::StoreU(hn::IfThenElseZero(ok, S1), d, out.S1 + o + i);
  hn::StoreU(hn::IfThenElseZero(ok, S2), d, out.S2 + o + i);
  hn::StoreU(hn::IfThenElseZero(ok, AopDeg(d, S2, S1)), d, out.AoP + o + i);
  hn::StoreU(hn::IfThenElseZero(ok, dop), d, out.DoP + o + i);
  hn::Store(hn::IfThenElseZero(ok, hn::Set(d, 1.0f)), d, valid + i);
}

HWY_INLINE void StoreValid(const float* valid, std::uint8_t* out) {
  for (std::size_t i = 0; i < kFusionChunk; ++i) out[i] = valid[i] > 0.0f ? 1 : 0;
}

// A double signal (the noise-free frames): step (1) pixel by pixel, then step (2) in lanes.
void FuseChunksF64(const FusionChunk* chunks, std::size_t count, const double* const* frames, const Constants& k,
                   const Layers& out) {
  const hn::ScalableTag<float> d;
  const std::size_t N = hn::Lanes(d);
  HWY_ALIGN float F[kFourCameras][kFusionChunk];
  HWY_ALIGN float seen[kFusionChunk];
  HWY_ALIGN float valid[kFusionChunk];
  for (std::size_t n = 0; n < count; ++n) {
    const FusionChunk& c = chunks[n];
    Samples(c, frames, k, F, seen);
    const std::size_t o = n * kFusionChunk;
    for (std::size_t i = 0; i < kFusionChunk; i += N) {
      const decltype(hn::Zero(d)) Fi[kFourCameras] = {hn::Load(d, F[0] + i), hn::Load(d, F[1] + i),
                                                      hn::Load(d, F[2] + i), hn::Load(d, F[3] + i)};
      Fuse(d, c, i, Fi, hn::Gt(hn::Load(d, seen + i), hn::Zero(d)), out, o, valid);
    }
    StoreValid(valid, out.valid + o);
  }
}

// Raw 16-bit frames: both steps in lanes. A pixel's two horizontal taps are one 32-bit word (little
// endian: the left tap in the low half), gathered at byte offset 2·index and 2·(index + width); the
// float operations are step (1)'s.
void FuseChunksU16(const FusionChunk* chunks, std::size_t count, const std::uint16_t* const* frames,
                   const Constants& k, const Layers& out) {
  static_assert(std::endian::native == std::endian::little, "the taps' words assume little endian");
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  const hn::RebindToUnsigned<decltype(d)> du;
  using V = decltype(hn::Zero(d));
  const std::size_t N = hn::Lanes(d);
  const auto none = hn::Set(di, -1);
  const auto low = hn::Set(du, 0xFFFFu);
  const auto below = hn::Set(di, static_cast<std::int32_t>(2 * k.width));
  HWY_ALIGN float valid[kFusionChunk];
  for (std::size_t n = 0; n < count; ++n) {
    const FusionChunk& c = chunks[n];
    const std::size_t o = n * kFusionChunk;
    for (std::size_t i = 0; i < kFusionChunk; i += N) {
      V F[kFourCameras];
      auto seen = hn::RebindMask(d, hn::Gt(hn::Load(di, c.index[0] + i), none));
      for (std::size_t j = 0; j < kFourCameras; ++j) {
        const auto index = hn::Load(di, c.index[j] + i);
        const auto sees = hn::Gt(index, none);
        seen = hn::And(seen, hn::RebindMask(d, sees));
        const auto offset = hn::IfThenElseZero(sees, hn::Add(index, index));
        const auto* base = reinterpret_cast<const std::int32_t*>(frames[j]);
        const auto w0 = hn::BitCast(du, hn::GatherOffset(di, base, offset));
        const auto w1 = hn::BitCast(du, hn::GatherOffset(di, base, hn::Add(offset, below)));
        const auto tap = [&](decltype(w0) v) { return hn::ConvertTo(d, hn::BitCast(di, v)); };
        const V p0 = tap(hn::And(w0, low)), p1 = tap(hn::ShiftRight<16>(w0)), p2 = tap(hn::And(w1, low)),
                p3 = tap(hn::ShiftRight<16>(w1));
        const V wx = hn::Load(d, c.wx[j] + i), wy = hn::Load(d, c.wy[j] + i);
        const V top = hn::Add(p0, hn::Mul(wx, hn::Sub(p1, p0))), bottom = hn::Add(p2, hn::Mul(wx, hn::Sub(p3, p2)));
        F[j] = hn::Mul(hn::Sub(hn::Add(top, hn::Mul(wy, hn::Sub(bottom, top))), hn::Set(d, k.b[j])),
                       hn::Set(d, k.inv_K[j]));
      }
      Fuse(d, c, i, F, seen, out, o, valid);
    }
    StoreValid(valid, out.valid + o);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace polrig
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace polrig::four_camera_lanes {

HWY_EXPORT(FuseChunksU16);
HWY_EXPORT(FuseChunksF64);

// The best path where avx2_paths() (the CPU has AVX2 and set_baseline_paths_only is off), else the
// build's baseline.
void fuse_chunks(const detail::FusionChunk* chunks, std::size_t count, const std::uint16_t* const frames[kFourCameras],
                 const Constants& c, const Layers& out) {
  if (avx2_paths()) return HWY_DYNAMIC_DISPATCH(FuseChunksU16)(chunks, count, frames, c, out);
  HWY_STATIC_DISPATCH(FuseChunksU16)(chunks, count, frames, c, out);
}
void fuse_chunks(const detail::FusionChunk* chunks, std::size_t count, const double* const frames[kFourCameras],
                 const Constants& c, const Layers& out) {
  if (avx2_paths()) return HWY_DYNAMIC_DISPATCH(FuseChunksF64)(chunks, count, frames, c, out);
  HWY_STATIC_DISPATCH(FuseChunksF64)(chunks, count, frames, c, out);
}

}  // namespace polrig::four_camera_lanes
#endif
