// The matcher's one hot loop: the sum of absolute differences of two byte runs, with one
// implementation per instruction set and the fastest the CPU has picked once, at first use. The
// library itself is built for baseline x86-64 (SSE2), so the binary runs on any x86-64; the AVX2 and
// AVX-512BW versions are compiled with GCC/clang `target` attributes and chosen with
// `__builtin_cpu_supports`. Every version returns the same integer (a sum of byte differences has
// no rounding), so the choice changes only the speed; test_sad.cpp checks them against `kScalar`.
// Internal to whiskeye_slam_core (the tests and vita-bench include it by path).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace whiskeye::slam::sad {

enum class Isa {
  kScalar,    // the reference: one byte at a time
  kBaseline,  // what the compiler makes of the plain loop for baseline x86-64 (SSE2 psadbw), or any CPU
  kAvx2,      // 32-byte vpsadbw, four accumulators
  kAvx512bw,  // 64-byte vpsadbw, four accumulators, masked tail
};

// Σ |a[i] − b[i]| over n bytes with the selected implementation. n < 2^24 (no overflow).
uint32_t sad_u8(const uint8_t* a, const uint8_t* b, size_t n);

// The same with a given implementation; supported(isa) must hold.
uint32_t sad_u8(Isa isa, const uint8_t* a, const uint8_t* b, size_t n);

// The SAD of every column shift's overlap at once, for two COLUMN-MAJOR images of w columns of h
// bytes: out[k] = Σ |cur(c) − st(c − shifts[k])| over the columns c where both exist
// (|shifts[k]| < w). The current image is prepared once (per match), the stored ones compared with
// it one after the other. With 11 shifts (±5, step 1: the configured matcher):
// - AVX-512BW: one pass over all the stored vectors, each loaded once and compared with its 11
//   partners, one register accumulator per shift. The partners are prepared per vector and shift,
//   64-byte aligned, zero where the shift has none; in the few edge vectors where some shift lacks a
//   partner the stored bytes are masked to zero as well (in registers: |0 − 0| adds nothing), so the
//   loop has no scalar edges and no tail. The bytes that follow the stored image (the store's next
//   row) are prefetched as it goes: the scan of a large store is bound by memory, not arithmetic.
// - AVX2: the same with 32-byte vectors, the edge vectors' stored bytes ANDed with byte masks.
// Otherwise one sad_u8() per shift. The same integers either way.
class ShiftedImage {
 public:
  // `cur` must outlive this object; `isa` must be supported.
  ShiftedImage(Isa isa, const uint8_t* cur, int w, int h, const int* shifts, int n_shifts);
  ShiftedImage(const uint8_t* cur, int w, int h, const int* shifts, int n_shifts);
  ShiftedImage(const ShiftedImage&) = delete;  // copies_ points into buf_
  ShiftedImage& operator=(const ShiftedImage&) = delete;
  void sads(const uint8_t* st, uint32_t* out) const;  // out: n_shifts values, in the shifts' order

 private:
  Isa isa_;
  const uint8_t* cur_;
  ptrdiff_t total_;
  std::vector<ptrdiff_t> d_;  // flat offset of each shift (shift·h)
  std::vector<uint8_t> buf_;  // the aligned copies (and AVX2's byte masks)
  // With 11 shifts on AVX-512BW (vec_ 64) or AVX2 (vec_ 32): the partners of stored vector v for
  // shift k at copies_ + (v·11 + k)·vec_, zero where it has none; nv_ vectors, every partner present
  // in [va_, vb_); outside it, which stored bytes count: masks_ (bits, 11 per edge vector) and for
  // AVX2 mask_bytes_ (0xFF/0x00, 11·32 per edge vector). The last vector holds in_last_ image bytes.
  const uint8_t* copies_ = nullptr;
  ptrdiff_t vec_ = 0, nv_ = 0, va_ = 0, vb_ = 0, in_last_ = 0;
  std::vector<uint64_t> masks_;
  const uint8_t* mask_bytes_ = nullptr;

  uint8_t* aligned_buffer(size_t bytes);  // buf_, zeroed, 64-byte aligned
  void prepare_padded(ptrdiff_t vec, ptrdiff_t lo_all, ptrdiff_t hi_all);
};

void shift_sads(Isa isa, const uint8_t* cur, const uint8_t* st, int w, int h, const int* shifts, int n_shifts,
                uint32_t* out);

bool supported(Isa isa);
// What sad_u8() uses: the fastest supported one unless force() chose another.
Isa selected();
// Makes sad_u8() use `isa` (which must be supported) and returns the previous choice: for the
// benchmark's same-run comparison of the implementations and for tests. Not for concurrent use.
Isa force(Isa isa);
const char* name(Isa isa);

}  // namespace whiskeye::slam::sad
