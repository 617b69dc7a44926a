// Sum of absolute byte differences, one version per instruction set (see sad.h). The AVX2 and
// AVX-512BW bodies are compiled for those targets only through `target` attributes; nothing else in
// the library assumes more than baseline x86-64.
#include "sad.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define WHISKEYE_SAD_X86 1
#include <immintrin.h>
#else
#define WHISKEYE_SAD_X86 0
#endif

namespace whiskeye::slam::sad {
namespace {

// The reference. Kept a byte at a time (the loop is opaque to the vectoriser through the volatile
// index bound) so a test of a fast version never compares it with itself.
uint32_t sad_scalar(const uint8_t* a, const uint8_t* b, size_t n) {
  uint32_t s = 0;
  volatile size_t end = n;
  for (size_t i = 0; i < end; ++i) s += static_cast<uint32_t>(std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i])));
  return s;
}

// GCC turns this exact shape into psadbw (SSE2) at -O3; unrolled so the loop overhead does not
// dominate one psadbw per 16 bytes.
uint32_t sad_baseline(const uint8_t* __restrict a, const uint8_t* __restrict b, size_t n) {
  uint32_t s = 0;
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC unroll 8
#endif
  for (size_t i = 0; i < n; ++i) s += static_cast<uint32_t>(std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i])));
  return s;
}

#if WHISKEYE_SAD_X86
// Loads as macros: a lambda or helper would not inherit the functions' target attributes.
#define WHISKEYE_LD256(p) _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))
#define WHISKEYE_LD512(p) _mm512_loadu_si512(p)

__attribute__((target("avx2"))) uint32_t sad_avx2(const uint8_t* a, const uint8_t* b, size_t n) {
  __m256i s0 = _mm256_setzero_si256(), s1 = s0, s2 = s0, s3 = s0;
  size_t i = 0;
  for (; i + 128 <= n; i += 128) {
    s0 = _mm256_add_epi64(s0, _mm256_sad_epu8(WHISKEYE_LD256(a + i), WHISKEYE_LD256(b + i)));
    s1 = _mm256_add_epi64(s1, _mm256_sad_epu8(WHISKEYE_LD256(a + i + 32), WHISKEYE_LD256(b + i + 32)));
    s2 = _mm256_add_epi64(s2, _mm256_sad_epu8(WHISKEYE_LD256(a + i + 64), WHISKEYE_LD256(b + i + 64)));
    s3 = _mm256_add_epi64(s3, _mm256_sad_epu8(WHISKEYE_LD256(a + i + 96), WHISKEYE_LD256(b + i + 96)));
  }
  for (; i + 32 <= n; i += 32) s0 = _mm256_add_epi64(s0, _mm256_sad_epu8(WHISKEYE_LD256(a + i), WHISKEYE_LD256(b + i)));
  const __m256i s = _mm256_add_epi64(_mm256_add_epi64(s0, s1), _mm256_add_epi64(s2, s3));
  __m128i t = _mm_add_epi64(_mm256_castsi256_si128(s), _mm256_extracti128_si256(s, 1));
  if (i + 16 <= n) {
    t = _mm_add_epi64(t, _mm_sad_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + i)),
                                      _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + i))));
    i += 16;
  }
  t = _mm_add_epi64(t, _mm_unpackhi_epi64(t, t));
  auto r = static_cast<uint32_t>(_mm_cvtsi128_si64(t));
  for (; i < n; ++i) r += static_cast<uint32_t>(std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i])));
  return r;
}

__attribute__((target("avx512bw"))) uint32_t sad_avx512bw(const uint8_t* a, const uint8_t* b, size_t n) {
  __m512i s0 = _mm512_setzero_si512(), s1 = s0, s2 = s0, s3 = s0;
  size_t i = 0;
  for (; i + 256 <= n; i += 256) {
    s0 = _mm512_add_epi64(s0, _mm512_sad_epu8(WHISKEYE_LD512(a + i), WHISKEYE_LD512(b + i)));
    s1 = _mm512_add_epi64(s1, _mm512_sad_epu8(WHISKEYE_LD512(a + i + 64), WHISKEYE_LD512(b + i + 64)));
    s2 = _mm512_add_epi64(s2, _mm512_sad_epu8(WHISKEYE_LD512(a + i + 128), WHISKEYE_LD512(b + i + 128)));
    s3 = _mm512_add_epi64(s3, _mm512_sad_epu8(WHISKEYE_LD512(a + i + 192), WHISKEYE_LD512(b + i + 192)));
  }
  for (; i + 64 <= n; i += 64) s0 = _mm512_add_epi64(s0, _mm512_sad_epu8(WHISKEYE_LD512(a + i), WHISKEYE_LD512(b + i)));
  if (i < n) {
    // Masked-off bytes read as 0 in both runs (and are never touched in memory): |0 − 0| adds nothing.
    const __mmask64 m = (uint64_t{1} << (n - i)) - 1;
    s1 = _mm512_add_epi64(s1, _mm512_sad_epu8(_mm512_maskz_loadu_epi8(m, a + i), _mm512_maskz_loadu_epi8(m, b + i)));
  }
  // Through memory: GCC 12's _mm512_reduce_add_epi64 trips its own -Wuninitialized (_mm256_undefined_si256).
  alignas(64) uint64_t lanes[8];
  _mm512_store_si512(lanes, _mm512_add_epi64(_mm512_add_epi64(s0, s1), _mm512_add_epi64(s2, s3)));
  uint64_t r = 0;
  for (const uint64_t l : lanes) r += l;
  return static_cast<uint32_t>(r);
}

// ShiftedImage::sads() for NS shifts. [j0, j1): stored bytes inside every shift's overlap, a whole
// number of vectors; there each stored vector is loaded once and compared with shift k's aligned
// copy of the current image (copies + k·stride, from j0 on), NS register accumulators (so every loop
// over them is unrolled). Then each shift's edges [lo_k, j0) and [j1, hi_k) of its overlap.
template <int NS>
__attribute__((target("avx512bw"))) void fused_avx512bw(const uint8_t* cur, const uint8_t* copies, size_t stride,
                                                         const uint8_t* st, ptrdiff_t total, ptrdiff_t j0,
                                                         ptrdiff_t j1, const ptrdiff_t* d, uint32_t* out) {
  __m512i acc[NS];
#pragma GCC unroll 16
  for (int k = 0; k < NS; ++k) acc[k] = _mm512_setzero_si512();
  for (ptrdiff_t j = j0; j < j1; j += 64) {
    const __m512i s = WHISKEYE_LD512(st + j);
    const uint8_t* c = copies + (j - j0);
#pragma GCC unroll 16
    for (int k = 0; k < NS; ++k) acc[k] = _mm512_add_epi64(acc[k], _mm512_sad_epu8(_mm512_load_si512(c + k * stride), s));
  }
  alignas(64) uint64_t lanes[NS][8];
#pragma GCC unroll 16
  for (int k = 0; k < NS; ++k) _mm512_store_si512(lanes[k], acc[k]);
  // The edges, the last vector of each run masked: masked lanes read as 0 in both images and are
  // never touched in memory (|0 − 0| adds nothing).
  for (int k = 0; k < NS; ++k) {
    const ptrdiff_t lo = std::max<ptrdiff_t>(0, -d[k]), hi = std::min(total, total - d[k]);
    __m512i e = _mm512_setzero_si512();
    for (const auto& [from, to] : {std::pair{lo, j0}, std::pair{j1, hi}}) {
      for (ptrdiff_t j = from; j < to; j += 64) {
        const __mmask64 m = to - j >= 64 ? ~uint64_t{0} : (uint64_t{1} << (to - j)) - 1;
        e = _mm512_add_epi64(e, _mm512_sad_epu8(_mm512_maskz_loadu_epi8(m, cur + j + d[k]),
                                                _mm512_maskz_loadu_epi8(m, st + j)));
      }
    }
    alignas(64) uint64_t el[8];
    _mm512_store_si512(el, e);
    uint64_t r = 0;
    for (int l = 0; l < 8; ++l) r += lanes[k][l] + el[l];
    out[k] = static_cast<uint32_t>(r);
  }
}

template <int NS>
__attribute__((target("avx2"))) void fused_avx2(const uint8_t* cur, const uint8_t* copies, size_t stride,
                                                const uint8_t* st, ptrdiff_t total, ptrdiff_t j0, ptrdiff_t j1,
                                                const ptrdiff_t* d, uint32_t* out) {
  __m256i acc[NS];
#pragma GCC unroll 16
  for (int k = 0; k < NS; ++k) acc[k] = _mm256_setzero_si256();
  for (ptrdiff_t j = j0; j < j1; j += 32) {
    const __m256i s = WHISKEYE_LD256(st + j);
    const uint8_t* c = copies + (j - j0);
#pragma GCC unroll 16
    for (int k = 0; k < NS; ++k) {
      acc[k] = _mm256_add_epi64(
          acc[k], _mm256_sad_epu8(_mm256_load_si256(reinterpret_cast<const __m256i*>(c + k * stride)), s));
    }
  }
  alignas(32) uint64_t lanes[NS][4];
#pragma GCC unroll 16
  for (int k = 0; k < NS; ++k) _mm256_store_si256(reinterpret_cast<__m256i*>(lanes[k]), acc[k]);
  for (int k = 0; k < NS; ++k) {
    const ptrdiff_t lo = std::max<ptrdiff_t>(0, -d[k]), hi = std::min(total, total - d[k]);
    out[k] = static_cast<uint32_t>(lanes[k][0] + lanes[k][1] + lanes[k][2] + lanes[k][3]) +
             sad_avx2(cur + lo + d[k], st + lo, static_cast<size_t>(j0 - lo)) +
             sad_avx2(cur + j1 + d[k], st + j1, static_cast<size_t>(hi - j1));
  }
}
#undef WHISKEYE_LD256
#undef WHISKEYE_LD512
#endif

using Fn = uint32_t (*)(const uint8_t*, const uint8_t*, size_t);

Fn fn_of(Isa isa) {
  switch (isa) {
    case Isa::kScalar:
      return sad_scalar;
    case Isa::kBaseline:
      return sad_baseline;
#if WHISKEYE_SAD_X86
    case Isa::kAvx2:
      return sad_avx2;
    case Isa::kAvx512bw:
      return sad_avx512bw;
#else
    case Isa::kAvx2:
    case Isa::kAvx512bw:
      break;
#endif
  }
  return sad_baseline;
}

Isa best_supported() {
  if (supported(Isa::kAvx512bw)) return Isa::kAvx512bw;
  if (supported(Isa::kAvx2)) return Isa::kAvx2;
  return Isa::kBaseline;
}

// Chosen before main() (a constant initialiser, then the first call), read with relaxed order: every
// value it can hold computes the same sums.
std::atomic<Isa>& current() {
  static std::atomic<Isa> isa{best_supported()};
  return isa;
}

}  // namespace

bool supported(Isa isa) {
  switch (isa) {
    case Isa::kScalar:
    case Isa::kBaseline:
      return true;
#if WHISKEYE_SAD_X86
    case Isa::kAvx2:
      __builtin_cpu_init();  // may run before main(), from another object's constructor
      return __builtin_cpu_supports("avx2") != 0;
    case Isa::kAvx512bw:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx512bw") != 0;
#else
    case Isa::kAvx2:
    case Isa::kAvx512bw:
      return false;
#endif
  }
  return false;
}

Isa selected() { return current().load(std::memory_order_relaxed); }

Isa force(Isa isa) { return current().exchange(supported(isa) ? isa : best_supported(), std::memory_order_relaxed); }

const char* name(Isa isa) {
  switch (isa) {
    case Isa::kScalar:
      return "scalar";
    case Isa::kBaseline:
      return "baseline";
    case Isa::kAvx2:
      return "avx2";
    case Isa::kAvx512bw:
      return "avx512bw";
  }
  return "?";
}

uint32_t sad_u8(const uint8_t* a, const uint8_t* b, size_t n) { return fn_of(selected())(a, b, n); }

namespace {
constexpr int kFused = 11;  // the shift count with a fused kernel
}  // namespace

ShiftedImage::ShiftedImage(const uint8_t* cur, int w, int h, const int* shifts, int n_shifts)
    : ShiftedImage(selected(), cur, w, h, shifts, n_shifts) {}

ShiftedImage::ShiftedImage(Isa isa, const uint8_t* cur, int w, int h, const int* shifts, int n_shifts)
    : isa_(isa), cur_(cur), total_(static_cast<ptrdiff_t>(w) * h) {
  ptrdiff_t lo_all = 0, hi_all = total_;  // the stored bytes every shift overlaps
  for (int k = 0; k < n_shifts; ++k) {
    d_.push_back(static_cast<ptrdiff_t>(shifts[k]) * h);
    lo_all = std::max(lo_all, -d_.back());
    hi_all = std::min(hi_all, total_ - d_.back());
  }
  const ptrdiff_t vec = isa == Isa::kAvx512bw ? 64 : isa == Isa::kAvx2 ? 32 : 0;
  if (!WHISKEYE_SAD_X86 || vec == 0 || n_shifts != kFused || hi_all - lo_all < 4 * vec) return;
  fused_ = true;
  j0_ = lo_all;
  j1_ = j0_ + (hi_all - lo_all) / vec * vec;
  stride_ = static_cast<size_t>(j1_ - j0_);  // a multiple of vec, so every copy starts aligned
  buf_.resize(stride_ * kFused + 64);
  const auto misalign = reinterpret_cast<uintptr_t>(buf_.data()) % 64;
  copies_ = buf_.data() + (misalign == 0 ? 0 : 64 - misalign);
  for (int k = 0; k < kFused; ++k) {
    std::copy(cur + j0_ + d_[static_cast<size_t>(k)], cur + j1_ + d_[static_cast<size_t>(k)],
              buf_.data() + (copies_ - buf_.data()) + static_cast<size_t>(k) * stride_);
  }
}

void ShiftedImage::sads(const uint8_t* st, uint32_t* out) const {
#if WHISKEYE_SAD_X86
  if (fused_ && isa_ == Isa::kAvx512bw) {
    fused_avx512bw<kFused>(cur_, copies_, stride_, st, total_, j0_, j1_, d_.data(), out);
    return;
  }
  if (fused_ && isa_ == Isa::kAvx2) {
    fused_avx2<kFused>(cur_, copies_, stride_, st, total_, j0_, j1_, d_.data(), out);
    return;
  }
#endif
  const Fn sad = fn_of(isa_);
  for (size_t k = 0; k < d_.size(); ++k) {
    const ptrdiff_t lo = std::max<ptrdiff_t>(0, -d_[k]), hi = std::min(total_, total_ - d_[k]);
    out[k] = hi > lo ? sad(cur_ + lo + d_[k], st + lo, static_cast<size_t>(hi - lo)) : 0;
  }
}

void shift_sads(Isa isa, const uint8_t* cur, const uint8_t* st, int w, int h, const int* shifts, int n_shifts,
                uint32_t* out) {
  ShiftedImage(isa, cur, w, h, shifts, n_shifts).sads(st, out);
}

uint32_t sad_u8(Isa isa, const uint8_t* a, const uint8_t* b, size_t n) { return fn_of(isa)(a, b, n); }

}  // namespace whiskeye::slam::sad
