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

// ShiftedImage::sads() for NS shifts on AVX-512BW: every stored vector v (64 bytes) loaded once and
// compared with the NS prepared copies of the current image (copies + (v·NS + k)·64: shift k's
// partner bytes, zero where shift k has none), one register accumulator per shift. In the interior
// [va, vb) every shift has a partner for every byte; in the edge vectors the stored bytes without a
// partner (and those past the image) are masked to zero too (masks, NS per edge vector), so they add
// |0 − 0|. `in_last`: how many bytes of the last vector lie inside the image (only those are read).
// The sums are exact integers, so this adds the same bytes as the plain loop. The bytes after the
// image are prefetched as it goes (the store's next row; see sad.h: a large store is memory-bound).
template <int NS>
__attribute__((target("avx512bw"))) void padded_avx512bw(const uint8_t* copies, const uint64_t* masks, ptrdiff_t nv,
                                                          ptrdiff_t va, ptrdiff_t vb, ptrdiff_t in_last,
                                                          const uint8_t* st, uint32_t* out) {
  const __mmask64 last = in_last == 64 ? ~uint64_t{0} : (uint64_t{1} << in_last) - 1;
  __m512i acc[NS];
#pragma GCC unroll 16
  for (int k = 0; k < NS; ++k) acc[k] = _mm512_setzero_si512();
  const uint64_t* m = masks;  // the edge vectors' masks, in the order they are visited
  for (ptrdiff_t v = 0; v < nv; ++v) {
    const uint8_t* c = copies + v * NS * 64;
    _mm_prefetch(reinterpret_cast<const char*>(st + (nv + v) * 64), _MM_HINT_T0);
    if (v >= va && v < vb) {
      const __m512i s = WHISKEYE_LD512(st + v * 64);
#pragma GCC unroll 16
      for (int k = 0; k < NS; ++k) acc[k] = _mm512_add_epi64(acc[k], _mm512_sad_epu8(_mm512_load_si512(c + k * 64), s));
    } else {
      // A plain load where the vector lies inside the image (a masked load would hide the stream
      // from the hardware prefetcher: it cost a third of the time at 10,000 templates), then masked
      // in registers.
      const __m512i s = v + 1 < nv ? WHISKEYE_LD512(st + v * 64) : _mm512_maskz_loadu_epi8(last, st + v * 64);
#pragma GCC unroll 16
      for (int k = 0; k < NS; ++k) {
        acc[k] = _mm512_add_epi64(acc[k], _mm512_sad_epu8(_mm512_load_si512(c + k * 64), _mm512_maskz_mov_epi8(m[k], s)));
      }
      m += NS;
    }
  }
  // Two shifts per vector (every lane and every shift's total is below 2^32: n < 2^24), then the
  // eight lanes of each pair added.
  alignas(64) uint64_t lanes[(NS + 1) / 2][8];
#pragma GCC unroll 16
  for (int k = 0; k < NS; k += 2) {
    // (maskz: GCC 12's _mm512_slli_epi64 trips its own -Wuninitialized, like its reduce in sad_avx512bw)
    const __m512i hi = k + 1 < NS ? _mm512_maskz_slli_epi64(0xFF, acc[std::min(k + 1, NS - 1)], 32) : _mm512_setzero_si512();
    _mm512_store_si512(lanes[k / 2], _mm512_add_epi64(acc[k], hi));
  }
  for (int k = 0; k < NS; k += 2) {
    uint64_t r = 0;
    for (const uint64_t l : lanes[k / 2]) r += l;
    out[k] = static_cast<uint32_t>(r);
    if (k + 1 < NS) out[k + 1] = static_cast<uint32_t>(r >> 32);
  }
}

// The same on AVX2 with 32-byte vectors: AVX2 has no byte masks, so an edge vector's stored bytes
// are ANDed with a byte mask (bytes, 32 per shift per edge vector: 0xFF where the shift has a
// partner), and the last vector, when the image ends inside it, is read through a zero-padded copy.
template <int NS>
__attribute__((target("avx2"))) void padded_avx2(const uint8_t* copies, const uint8_t* bytes, ptrdiff_t nv,
                                                 ptrdiff_t va, ptrdiff_t vb, ptrdiff_t in_last, const uint8_t* st,
                                                 uint32_t* out) {
  __m256i acc[NS];
#pragma GCC unroll 16
  for (int k = 0; k < NS; ++k) acc[k] = _mm256_setzero_si256();
  const uint8_t* m = bytes;
  for (ptrdiff_t v = 0; v < nv; ++v) {
    const uint8_t* c = copies + v * NS * 32;
    _mm_prefetch(reinterpret_cast<const char*>(st + (nv + v) * 32), _MM_HINT_T0);
    if (v >= va && v < vb) {
      const __m256i s = WHISKEYE_LD256(st + v * 32);
#pragma GCC unroll 16
      for (int k = 0; k < NS; ++k) {
        acc[k] = _mm256_add_epi64(acc[k], _mm256_sad_epu8(_mm256_load_si256(reinterpret_cast<const __m256i*>(c + k * 32)), s));
      }
    } else {
      alignas(32) uint8_t tail[32] = {};
      const bool inside = v + 1 < nv || in_last == 32;
      if (!inside) std::copy(st + v * 32, st + v * 32 + in_last, tail);
      const __m256i s = inside ? WHISKEYE_LD256(st + v * 32) : _mm256_load_si256(reinterpret_cast<const __m256i*>(tail));
#pragma GCC unroll 16
      for (int k = 0; k < NS; ++k) {
        const __m256i mk = _mm256_load_si256(reinterpret_cast<const __m256i*>(m + k * 32));
        acc[k] = _mm256_add_epi64(acc[k], _mm256_sad_epu8(_mm256_load_si256(reinterpret_cast<const __m256i*>(c + k * 32)),
                                                          _mm256_and_si256(s, mk)));
      }
      m += NS * 32;
    }
  }
  alignas(32) uint64_t lanes[NS][4];
#pragma GCC unroll 16
  for (int k = 0; k < NS; ++k) _mm256_store_si256(reinterpret_cast<__m256i*>(lanes[k]), acc[k]);
  for (int k = 0; k < NS; ++k) out[k] = static_cast<uint32_t>(lanes[k][0] + lanes[k][1] + lanes[k][2] + lanes[k][3]);
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
  if (WHISKEYE_SAD_X86 && n_shifts == kFused && (isa == Isa::kAvx512bw || isa == Isa::kAvx2)) {
    prepare_padded(isa == Isa::kAvx512bw ? 64 : 32, lo_all, hi_all);
  }
}

uint8_t* ShiftedImage::aligned_buffer(size_t bytes) {
  buf_.assign(bytes + 64, 0);
  const auto misalign = reinterpret_cast<uintptr_t>(buf_.data()) % 64;
  return buf_.data() + (misalign == 0 ? 0 : 64 - misalign);
}

void ShiftedImage::prepare_padded(ptrdiff_t vec, ptrdiff_t lo_all, ptrdiff_t hi_all) {
  vec_ = vec;
  nv_ = (total_ + vec - 1) / vec;
  va_ = std::min(nv_, (lo_all + vec - 1) / vec);  // [va_, vb_): every byte has every shift's partner
  vb_ = std::clamp(hi_all / vec, va_, nv_);
  in_last_ = total_ - (nv_ - 1) * vec;  // 1..vec bytes
  const auto ns = static_cast<ptrdiff_t>(d_.size());
  // One aligned buffer: the partners, then (for AVX2) the edge vectors' byte masks.
  const ptrdiff_t copy_bytes = nv_ * ns * vec, edge_vectors = nv_ - (vb_ - va_);
  uint8_t* copies = aligned_buffer(static_cast<size_t>(copy_bytes + (vec == 32 ? edge_vectors * ns * vec : 0)));
  copies_ = copies;
  uint8_t* bytes = copies + copy_bytes;
  mask_bytes_ = bytes;
  masks_.clear();
  for (ptrdiff_t v = 0; v < nv_; ++v) {
    const bool edge = v < va_ || v >= vb_;
    for (ptrdiff_t k = 0; k < ns; ++k) {
      // Shift k's partners exist for the stored bytes [lo, hi); this vector holds [a, b) of them.
      const ptrdiff_t d = d_[static_cast<size_t>(k)];
      const ptrdiff_t a = std::max({v * vec, ptrdiff_t{0}, -d}), b = std::min({v * vec + vec, total_, total_ - d});
      if (a < b) std::copy(cur_ + a + d, cur_ + b + d, copies + (v * ns + k) * vec + (a - v * vec));
      if (!edge) continue;
      const ptrdiff_t n = std::max(ptrdiff_t{0}, b - a);
      masks_.push_back(n == 0 ? 0 : (n == 64 ? ~uint64_t{0} : (uint64_t{1} << n) - 1) << (a - v * vec));
      if (vec == 32) {
        if (n > 0) std::fill(bytes + (a - v * vec), bytes + (b - v * vec), uint8_t{0xFF});
        bytes += vec;
      }
    }
  }
}

void ShiftedImage::sads(const uint8_t* st, uint32_t* out) const {
#if WHISKEYE_SAD_X86
  if (vec_ == 64) {
    padded_avx512bw<kFused>(copies_, masks_.data(), nv_, va_, vb_, in_last_, st, out);
    return;
  }
  if (vec_ == 32) {
    padded_avx2<kFused>(copies_, mask_bytes_, nv_, va_, vb_, in_last_, st, out);
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
