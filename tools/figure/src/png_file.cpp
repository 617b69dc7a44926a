// PNG files with zlib (see png_file.h): one IDAT chunk, every row with filter 0 (none).
#include "whiskeye/figure/png_file.h"

#include <zlib.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace whiskeye::figure {

namespace {

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<uint8_t>(v >> shift));
}

// length, type, data, CRC of type and data.
void put_chunk(std::vector<uint8_t>& out, const char (&type)[5], const std::vector<uint8_t>& data) {
  put_u32(out, static_cast<uint32_t>(data.size()));
  const std::size_t type_at = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  const uLong crc = crc32(0L, out.data() + type_at, static_cast<uInt>(out.size() - type_at));
  put_u32(out, static_cast<uint32_t>(crc));
}

}  // namespace

void write_png(const std::string& path, const uint8_t* pixels, int width, int height, int channels,
               std::size_t stride) {
  if (width <= 0 || height <= 0 || (channels != 1 && channels != 3)) {
    throw std::runtime_error(path + ": cannot write a PNG of " + std::to_string(width) + "x" + std::to_string(height) +
                             " pixels of " + std::to_string(channels) + " channels");
  }
  // Rows as PNG wants them: a filter byte, then grey or R, G, B.
  const std::size_t row_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  std::vector<uint8_t> raw((row_bytes + 1) * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    const uint8_t* in = pixels + static_cast<std::size_t>(y) * stride;
    uint8_t* out = &raw[static_cast<std::size_t>(y) * (row_bytes + 1)];
    *out++ = 0;
    if (channels == 1) {
      std::copy(in, in + row_bytes, out);
    } else {
      for (int x = 0; x < width; ++x, in += 3, out += 3) {
        out[0] = in[2];
        out[1] = in[1];
        out[2] = in[0];
      }
    }
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<uint8_t> packed(packed_size);
  if (compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()), Z_DEFAULT_COMPRESSION) != Z_OK) {
    throw std::runtime_error(path + ": cannot compress the PNG");
  }
  packed.resize(packed_size);

  std::vector<uint8_t> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<uint8_t> header;
  put_u32(header, static_cast<uint32_t>(width));
  put_u32(header, static_cast<uint32_t>(height));
  header.push_back(8);                                        // bit depth
  header.push_back(channels == 1 ? 0 : 2);                    // colour type: grey, RGB
  header.insert(header.end(), {0, 0, 0});                     // deflate, adaptive filtering, no interlace
  put_chunk(png, "IHDR", header);
  put_chunk(png, "IDAT", packed);
  put_chunk(png, "IEND", {});
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  file.close();
  if (!file) throw std::runtime_error(path + ": cannot write the PNG");
}

}  // namespace whiskeye::figure
