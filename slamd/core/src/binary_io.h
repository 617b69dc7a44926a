// Little-endian binary writer/reader for the core's checkpoint format (internal). Every value is
// written in little-endian byte order whatever the host, so a checkpoint written on one machine
// restores on another. Floats/doubles are written as their IEEE-754 bit patterns, which makes a
// restore bit-exact. On a little-endian host an array is one memcpy (a 10,000-template map is
// 30 MB, checkpointed every cycle); elsewhere each value is swapped byte by byte.
#pragma once

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
void put(std::vector<uint8_t>& out, T v) {
  static_assert(std::is_arithmetic_v<T>);
  if constexpr (std::endian::native == std::endian::little) {
    const size_t at = out.size();
    out.resize(at + sizeof(T));
    std::memcpy(out.data() + at, &v, sizeof(T));
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

template <typename T>
void put_vec(std::vector<uint8_t>& out, const std::vector<T>& v) {
  put<uint64_t>(out, v.size());
  if constexpr (std::endian::native == std::endian::little) {
    const size_t at = out.size();
    out.resize(at + v.size() * sizeof(T));
    if (!v.empty()) std::memcpy(out.data() + at, v.data(), v.size() * sizeof(T));
  } else {
    for (const T& x : v) put<T>(out, x);
  }
}

template <typename T>
std::vector<T> get_vec(const std::vector<uint8_t>& in, size_t& pos) {
  const auto n = get<uint64_t>(in, pos);
  if (n > (in.size() - pos) / sizeof(T)) {
    throw std::runtime_error("checkpoint: array of " + std::to_string(n) + " elements at byte " + std::to_string(pos) +
                             " is longer than the data");
  }
  std::vector<T> v(static_cast<size_t>(n));
  if constexpr (std::endian::native == std::endian::little) {
    if (n != 0) std::memcpy(v.data(), in.data() + pos, v.size() * sizeof(T));
    pos += v.size() * sizeof(T);
  } else {
    for (T& x : v) x = get<T>(in, pos);
  }
  return v;
}

}  // namespace whiskeye::slam::bin
