// Fixed-length rows (one per template) appended in chunks that never move. A std::vector holding
// 10,000 templates' pixels (25 MB) copies all of them when it outgrows its capacity, which made the
// cycle that added the template take 18 ms instead of 5; here growing adds a chunk and copies nothing. Each row is
// contiguous, so the matcher's per-template loops are unchanged. Chunks start on a 64-byte boundary, so
// a row whose length is a multiple of 64 bytes (a 64×40 template: 2,560) never has a vector load
// straddle two cache lines (that cost the scan about a tenth at 10,000 templates).
#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace whiskeye::slam {

template <typename T>
class RowStore {
 public:
  using value_type = T;
  RowStore() = default;
  explicit RowStore(size_t row_length) : len_(row_length) {}
  RowStore(const RowStore& o) : len_(o.len_), rows_(o.rows_) {
    for (const auto& c : o.chunks_) {
      chunks_.push_back(new_chunk(kRowsPerChunk * len_));
      std::copy(c.get(), c.get() + kRowsPerChunk * len_, chunks_.back().get());
    }
  }
  RowStore& operator=(const RowStore& o) {
    if (this != &o) *this = RowStore(o);
    return *this;
  }
  RowStore(RowStore&&) noexcept = default;
  RowStore& operator=(RowStore&&) noexcept = default;

  size_t rows() const { return rows_; }
  size_t row_length() const { return len_; }
  size_t elements() const { return rows_ * len_; }

  // A new zero-filled row; valid for the store's lifetime (nullptr when rows are empty).
  T* append() {
    if (rows_ % kRowsPerChunk == 0 && len_ > 0) chunks_.push_back(new_chunk(kRowsPerChunk * len_));
    ++rows_;
    return row(rows_ - 1);
  }
  T* row(size_t i) { return len_ == 0 ? nullptr : chunks_[i / kRowsPerChunk].get() + (i % kRowsPerChunk) * len_; }
  const T* row(size_t i) const {
    return len_ == 0 ? nullptr : chunks_[i / kRowsPerChunk].get() + (i % kRowsPerChunk) * len_;
  }

  // f(data, count) over the rows in order, as few contiguous runs as there are chunks.
  template <typename F>
  void for_each_run(F f) const {
    for (size_t c = 0; c * kRowsPerChunk < rows_ && len_ > 0; ++c) {
      f(static_cast<const T*>(chunks_[c].get()), std::min(kRowsPerChunk, rows_ - c * kRowsPerChunk) * len_);
    }
  }

  bool operator==(const RowStore& o) const {
    if (len_ != o.len_ || rows_ != o.rows_) return false;
    for (size_t i = 0; i < rows_ && len_ > 0; ++i) {
      if (!std::equal(row(i), row(i) + len_, o.row(i))) return false;
    }
    return true;
  }

 private:
  static constexpr size_t kRowsPerChunk = 256;
  static constexpr std::align_val_t kAlign{64};
  static_assert(std::is_trivial_v<T>, "chunks are raw, zero-filled storage");
  struct Free {
    void operator()(T* p) const { ::operator delete[](p, kAlign); }
  };
  using Chunk = std::unique_ptr<T[], Free>;
  static Chunk new_chunk(size_t n) {
    Chunk c(static_cast<T*>(::operator new[](n * sizeof(T), kAlign)));
    std::fill(c.get(), c.get() + n, T{});
    return c;
  }
  size_t len_ = 0;
  size_t rows_ = 0;
  std::vector<Chunk> chunks_;
};

}  // namespace whiskeye::slam
