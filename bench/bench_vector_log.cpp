// The library comparison for the CS study's logarithms (issue 11): 1080 natural logarithms of
// study-like ratios per iteration, by each candidate, in one run. items_per_second is 1080-log
// batches per CPU second, directly comparable with BM_CsSummary's points per second.
//   build/bench/polrig_bench --benchmark_filter='VectorLog'
// Variants named _FMA use fused multiply-adds and give results that differ (at the ulp level)
// from the variants without; see src/study/vector_log.cpp for the choice.
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <benchmark/benchmark.h>
#include <immintrin.h>
#include <xsimd/xsimd.hpp>
#include <sleef.h>
// sleef.h declares its AVX variants only when the whole file targets AVX; they are called here
// only from functions with those targets, on CPUs that have them.
extern "C" {
__attribute__((target("avx"))) __m256d Sleef_logd4_u10avx(__m256d);
__attribute__((target("avx2,fma"))) __m256d Sleef_logd4_u10avx2(__m256d);
__attribute__((target("avx512f"))) __m512d Sleef_logd8_u10avx512fnofma(__m512d);
}

#include "polrig/vector_log.h"
#include "vector_log_cases.h"

namespace {
using namespace polrig_bench;

template <class F>
void run_case(benchmark::State& state, F log_array) {
  const std::vector<double> x = study_like_ratios();
  std::vector<double> y(x.size());
  for (auto _ : state) {
    if (!log_array(x.data(), y.data(), x.size())) {
      state.SkipWithError("this CPU lacks the instructions");
      break;
    }
    benchmark::DoNotOptimize(y.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_VectorLog_ScalarStdLog(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) y[i] = std::log(x[i]);
    return true;
  });
}
BENCHMARK(BM_VectorLog_ScalarStdLog);

// What the CS study uses (polrig/vector_log.h: Highway, dispatched, without FMA).
void BM_VectorLog_Polrig(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    polrig::log_array(x, y, n);
    return true;
  });
}
BENCHMARK(BM_VectorLog_Polrig);

void BM_VectorLog_EigenArray_SSE2(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    Eigen::Map<Eigen::ArrayXd>(y, static_cast<Eigen::Index>(n)) =
        Eigen::Map<const Eigen::ArrayXd>(x, static_cast<Eigen::Index>(n)).log();
    return true;
  });
}
BENCHMARK(BM_VectorLog_EigenArray_SSE2);

// The CPU is asked here, in baseline code: the AVX2 file's own code may use AVX2 anywhere.
void BM_VectorLog_Eigen_AVX2(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    return __builtin_cpu_supports("avx2") && eigen_avx2_log(x, y, n);
  });
}
BENCHMARK(BM_VectorLog_Eigen_AVX2);

void BM_VectorLog_Xsimd_SSE2(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    using batch = xsimd::batch<double, xsimd::sse2>;
    for (std::size_t i = 0; i + batch::size <= n; i += batch::size)
      xsimd::log(batch::load_unaligned(x + i)).store_unaligned(y + i);
    return true;
  });
}
BENCHMARK(BM_VectorLog_Xsimd_SSE2);

void BM_VectorLog_Xsimd_AVX2(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    return __builtin_cpu_supports("avx2") && xsimd_avx2_log(x, y, n);
  });
}
BENCHMARK(BM_VectorLog_Xsimd_AVX2);

void BM_VectorLog_Highway_BestTarget_FMA(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    highway_log(x, y, n);
    return true;
  });
}
BENCHMARK(BM_VectorLog_Highway_BestTarget_FMA);

void BM_VectorLog_Sleef_SSE2_u10(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    for (std::size_t i = 0; i + 2 <= n; i += 2) _mm_storeu_pd(y + i, Sleef_logd2_u10sse2(_mm_loadu_pd(x + i)));
    return true;
  });
}
BENCHMARK(BM_VectorLog_Sleef_SSE2_u10);

void BM_VectorLog_Sleef_SSE2_u35(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    for (std::size_t i = 0; i + 2 <= n; i += 2) _mm_storeu_pd(y + i, Sleef_logd2_u35sse2(_mm_loadu_pd(x + i)));
    return true;
  });
}
BENCHMARK(BM_VectorLog_Sleef_SSE2_u35);

__attribute__((target("avx"))) void sleef_avx_u10(const double* x, double* y, std::size_t n) {
  for (std::size_t i = 0; i + 4 <= n; i += 4) _mm256_storeu_pd(y + i, Sleef_logd4_u10avx(_mm256_loadu_pd(x + i)));
}
void BM_VectorLog_Sleef_AVX_u10(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    if (!__builtin_cpu_supports("avx")) return false;
    sleef_avx_u10(x, y, n);
    return true;
  });
}
BENCHMARK(BM_VectorLog_Sleef_AVX_u10);

__attribute__((target("avx2,fma"))) void sleef_avx2_u10(const double* x, double* y, std::size_t n) {
  for (std::size_t i = 0; i + 4 <= n; i += 4) _mm256_storeu_pd(y + i, Sleef_logd4_u10avx2(_mm256_loadu_pd(x + i)));
}
void BM_VectorLog_Sleef_AVX2_u10_FMA(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return false;
    sleef_avx2_u10(x, y, n);
    return true;
  });
}
BENCHMARK(BM_VectorLog_Sleef_AVX2_u10_FMA);

__attribute__((target("avx512f"))) void sleef_avx512_u10(const double* x, double* y, std::size_t n) {
  for (std::size_t i = 0; i + 8 <= n; i += 8)
    _mm512_storeu_pd(y + i, Sleef_logd8_u10avx512fnofma(_mm512_loadu_pd(x + i)));
}
void BM_VectorLog_Sleef_AVX512nofma_u10(benchmark::State& state) {
  run_case(state, [](const double* x, double* y, std::size_t n) {
    if (!__builtin_cpu_supports("avx512f")) return false;
    sleef_avx512_u10(x, y, n);
    return true;
  });
}
BENCHMARK(BM_VectorLog_Sleef_AVX512nofma_u10);

}  // namespace
