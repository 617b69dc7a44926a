// Little-endian binary writer/reader for the core's checkpoint format (internal). Every value is
// written in little-endian byte order whatever the host, so a checkpoint written on one machine
// restores on another. Floats/doubles are written as their IEEE-754 bit patterns, which makes a
// restore bit-exact. On a little-endian host an array is one memcpy (a 10,000-template map is
// 30 MB, checkpointed every cycle); elsewhere each value is swapped byte by byte.
#pragma once

#include "whiskeye/slam/row_store.h"

#include <bit>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace whiskeye::slam::bin {

// The unsigned integer with T's size, to move T's bits byte by byte.
template <typename T>
using Bits = std::conditional_t<sizeof(T) == 1, uint8_t,
             std::conditional_t<sizeof(T) == 2, uint16_t, std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>>;

template <typename T>
void put_array(std::vector<uint8_t>& out, const T* data, size_t n);

template <typename T>
void put(std::vector<uint8_t>& out, T v) {
  static_assert(std::is_arithmetic_v<T>);
  if constexpr (std::endian::native == std::endian::little) {
    put_array(out, &v, 1);
  } else {
    Bits<T> u;
    std::memcpy(&u, &v, sizeof(T));
    for (size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<uint8_t>(u >> (8 * i)));
  }
}

template <typename T>
T get(const std::vector<uint8_t>& in, size_t& pos) {
  static_assert(std::is_arithmetic_v<T>);
  if (pos + sizeof(T) > in.size()) throw std::runtime_error("checkpoint truncated at byte " + std::to_string(pos));
  using U = Bits<T>;
  U u = 0;
  for (size_t i = 0; i < sizeof(T); ++i) u = static_cast<U>(u | (static_cast<U>(in[pos + i]) << (8 * i)));
  pos += sizeof(T);
  T v;
  std::memcpy(&v, &u, sizeof(T));
  return v;
}

// n values from `data`, without a count.
template <typename T>
void put_array(std::vector<uint8_t>& out, const T* data, size_t n) {
  if constexpr (std::endian::native == std::endian::little) {
    const size_t at = out.size();
    out.resize(at + n * sizeof(T));
    if (n != 0) std::memcpy(out.data() + at, data, n * sizeof(T));
  } else {
    for (size_t i = 0; i < n; ++i) put<T>(out, data[i]);
  }
}

// n values into `data`; the caller has checked that they are there.
template <typename T>
void get_array(const std::vector<uint8_t>& in, size_t& pos, T* data, size_t n) {
  if constexpr (std::endian::native == std::endian::little) {
    if (n != 0) std::memcpy(data, in.data() + pos, n * sizeof(T));
    pos += n * sizeof(T);
  } else {
    for (size_t i = 0; i < n; ++i) data[i] = get<T>(in, pos);
  }
}

// An array's count as uint64 at `pos`, checked against the bytes left.
template <typename T>
size_t get_count(const std::vector<uint8_t>& in, size_t& pos) {
  const auto n = get<uint64_t>(in, pos);
  if (n > (in.size() - pos) / sizeof(T)) {
    throw std::runtime_error("checkpoint: array of " + std::to_string(n) + " elements at byte " + std::to_string(pos) +
                             " is longer than the data");
  }
  return static_cast<size_t>(n);
}

template <typename T>
void put_vec(std::vector<uint8_t>& out, const std::vector<T>& v) {
  put<uint64_t>(out, v.size());
  put_array(out, v.data(), v.size());
}

template <typename T>
std::vector<T> get_vec(const std::vector<uint8_t>& in, size_t& pos) {
  std::vector<T> v(get_count<T>(in, pos));
  get_array(in, pos, v.data(), v.size());
  return v;
}

// A RowStore as put_vec() writes the same values in one vector: the count, then every row in order.
template <typename T>
void put_rows(std::vector<uint8_t>& out, const RowStore<T>& rows) {
  put<uint64_t>(out, rows.elements());
  rows.for_each_run([&](const T* data, size_t n) { put_array(out, data, n); });
}

// Reads what put_rows() (or put_vec()) wrote into `rows` (empty, with its row length set).
template <typename T>
void get_rows(const std::vector<uint8_t>& in, size_t& pos, RowStore<T>& rows) {
  const size_t at = pos;
  const size_t n = get_count<T>(in, pos);
  const size_t len = rows.row_length();
  if (len == 0 ? n != 0 : n % len != 0) {
    throw std::runtime_error("checkpoint: array of " + std::to_string(n) + " elements at byte " + std::to_string(at) +
                             " is not whole rows of " + std::to_string(len));
  }
  for (size_t r = 0; len != 0 && r < n / len; ++r) get_array(in, pos, rows.append(), len);
}

}  // namespace whiskeye::slam::bin
