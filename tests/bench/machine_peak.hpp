// The machine's own fp32 peak, measured: a loop of independent fused multiply-adds on every
// thread at once, with the widest vectors this CPU has (chosen at run time: AVX-512, AVX2 +
// FMA, or SSE2 multiply and add), so that the network benchmarks can say what share of the
// hardware they reach on whatever processor they run (the machines differ from day to day).
#pragma once

#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

namespace qte::bench {

struct Peak {
  double gflops = 0;  // fp32 FLOP/s of all threads together, 1e9
  std::string isa;    // the instructions the loop used
};

namespace peak_detail {

constexpr int kAccumulators = 12;  // enough independent chains to hide the FMA latency
constexpr long kIterations = 10'000'000;

// Each returns a value depending on every accumulator, so nothing is optimised away.
__attribute__((target("avx512f"))) inline float loop_avx512() {
  __m512 acc[kAccumulators];
  for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm512_set1_ps(0.001f * static_cast<float>(i));
  const __m512 a = _mm512_set1_ps(0.999999f), b = _mm512_set1_ps(1e-7f);
  for (long n = 0; n < kIterations; ++n)
    for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm512_fmadd_ps(acc[i], a, b);
  __m512 sum = acc[0];
  for (int i = 1; i < kAccumulators; ++i) sum = _mm512_add_ps(sum, acc[i]);
  float out[16];
  _mm512_storeu_ps(out, sum);
  return out[0] + out[15];
}

__attribute__((target("avx2,fma"))) inline float loop_avx2() {
  __m256 acc[kAccumulators];
  for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm256_set1_ps(0.001f * static_cast<float>(i));
  const __m256 a = _mm256_set1_ps(0.999999f), b = _mm256_set1_ps(1e-7f);
  for (long n = 0; n < kIterations; ++n)
    for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm256_fmadd_ps(acc[i], a, b);
  __m256 sum = acc[0];
  for (int i = 1; i < kAccumulators; ++i) sum = _mm256_add_ps(sum, acc[i]);
  float out[8];
  _mm256_storeu_ps(out, sum);
  return out[0] + out[7];
}

inline float loop_sse2() {  // x86-64's baseline: a multiply and an add (2 FLOPs a lane as well)
  __m128 acc[kAccumulators];
  for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm_set1_ps(0.001f * static_cast<float>(i));
  const __m128 a = _mm_set1_ps(0.999999f), b = _mm_set1_ps(1e-7f);
  for (long n = 0; n < kIterations; ++n)
    for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm_add_ps(_mm_mul_ps(acc[i], a), b);
  __m128 sum = acc[0];
  for (int i = 1; i < kAccumulators; ++i) sum = _mm_add_ps(sum, acc[i]);
  return _mm_cvtss_f32(sum);
}

// bf16 dot products with fp32 sums (AVX-512 BF16's vdpbf16ps): per lane and instruction two
// products and their two sums, 4 FLOPs.
__attribute__((target("avx512f,avx512bf16"))) inline float loop_bf16() {
  __m512 acc[kAccumulators];
  for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm512_set1_ps(0.001f * static_cast<float>(i));
  const __m512bh a = (__m512bh)_mm512_set1_epi16(0x3f80), b = (__m512bh)_mm512_set1_epi16(0x3380);  // 1, ~6e-8
  for (long n = 0; n < kIterations; ++n)
    for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm512_dpbf16_ps(acc[i], a, b);
  __m512 sum = acc[0];
  for (int i = 1; i < kAccumulators; ++i) sum = _mm512_add_ps(sum, acc[i]);
  float out[16];
  _mm512_storeu_ps(out, sum);
  return out[0] + out[15];
}

// The loop on `threads` threads at once, five times, the fastest kept (other work on a shared
// machine can only slow it down): FLOP/s given the loop's FLOPs per iteration and thread.
inline double fastest_gflops(float (*loop)(), double flops_per_iteration, int threads) {
  std::vector<float> sink(threads);
  double best = 0;
  for (int attempt = 0; attempt < 5; ++attempt) {
    std::vector<std::thread> pool;
    const auto t0 = std::chrono::steady_clock::now();
    for (int t = 0; t < threads; ++t) pool.emplace_back([&, t] { sink[t] = loop(); });
    for (auto& th : pool) th.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best = std::max(best, flops_per_iteration * static_cast<double>(kIterations) * threads / seconds / 1e9);
  }
  volatile float keep = sink[0];
  (void)keep;
  return best;
}

}  // namespace peak_detail

// fp32: FLOPs = 2 per lane per multiply-add.
inline Peak measure_fp32_peak(int threads) {
  using namespace peak_detail;
  float (*loop)() = loop_sse2;
  int lanes = 4;
  Peak peak{0, "SSE2 mul+add"};
  if (__builtin_cpu_supports("avx512f")) {
    loop = loop_avx512, lanes = 16, peak.isa = "AVX-512 FMA";
  } else if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    loop = loop_avx2, lanes = 8, peak.isa = "AVX2 FMA";
  }
  peak.gflops = fastest_gflops(loop, 2.0 * lanes * kAccumulators, threads);
  return peak;
}

// The bf16 peak (bf16 products, fp32 sums) where the processor has AVX-512 BF16; gflops 0
// elsewhere.
inline Peak measure_bf16_peak(int threads) {
  using namespace peak_detail;
  if (!__builtin_cpu_supports("avx512bf16")) return {0, "none"};
  return {fastest_gflops(loop_bf16, 4.0 * 16 * kAccumulators, threads), "AVX-512 BF16 vdpbf16ps"};
}

}  // namespace qte::bench
