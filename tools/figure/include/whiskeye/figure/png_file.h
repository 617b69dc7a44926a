// PNG files written with zlib alone (every Figure's, vita-sim's --plot-views and --frames-dir): OpenCV's
// imgcodecs would load 117 more shared libraries (GDAL, Poppler, HDF5, ...) at every start of the
// program, ≈ 70 ms of CPU and 120 ms of wall time in vita-sim, for optional side outputs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace whiskeye::figure {

// An 8-bit image as a PNG file: `channels` 1 (grey) or 3 (stored B, G, R, as OpenCV holds it),
// `stride` bytes between rows. Throws std::runtime_error naming `path` when it cannot be written.
void write_png(const std::string& path, const uint8_t* pixels, int width, int height, int channels,
               std::size_t stride);

}  // namespace whiskeye::figure
