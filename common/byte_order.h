// Byte order helpers for file formats.
#ifndef SHEETMESH_COMMON_BYTE_ORDER_H_
#define SHEETMESH_COMMON_BYTE_ORDER_H_

#include <algorithm>
#include <bit>
#include <cstddef>
#include <span>

namespace sheetmesh {

// True when this machine is little-endian.
constexpr bool NativeIsLittleEndian() { return std::endian::native == std::endian::little; }

// Swaps the byte order of every `width`-byte element of `data` in place (width 1: no-op).
inline void SwapBytes(std::span<std::byte> data, int width) {
  if (width <= 1) return;
  for (size_t i = 0; i + width <= data.size(); i += width) {
    std::reverse(data.begin() + i, data.begin() + i + width);
  }
}

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_BYTE_ORDER_H_
