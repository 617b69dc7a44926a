// A JPEG's marker structure, read without decoding: whether it ends, whether it is put together as a
// JPEG at all, and the frame size its header claims. camerad refuses a damaged MJPEG frame with it
// before it publishes it, counting it; slamd's decoder asks libjpeg for the header it decodes (a
// second parser's answer is not the one to check) and reads only ends_with_eoi() here. Pure; no
// allocation.
#pragma once

#include <cstdint>
#include <span>

namespace whiskeye::jpeg {

// Whether the data ends with the end-of-image marker (FF D9), zero padding after it ignored (some
// UVC cameras pad their buffers).
bool ends_with_eoi(std::span<const uint8_t> d);

// What check_structure() found. kWhole: SOI, header segments with lengths inside the data, a frame
// header (SOF) before the first scan, entropy-coded data holding only what a scan may hold (stuffed
// FF 00, restart markers, fill bytes), more segments or scans, and EOI at the end (zero padding after
// it ignored).
enum class Structure {
  kWhole,
  kNoStartMarker,  // does not begin with SOI (FF D8)
  kBadHeader,      // before the first scan: a segment that does not parse, no SOF, no scan
  kCutShort,       // no EOI at the end: the frame stops mid-way
  kDamagedData,    // after the first scan began: a marker no JPEG holds there, a segment running past
                   // the end, or bytes after an early EOI
};
const char* structure_name(Structure s);

struct FrameSize {
  int width = 0, height = 0;
};
// Linear in the size (one memchr-driven pass over the entropy-coded data). With `size`: the frame
// size in the first SOF segment of that walk, {0, 0} unless kWhole. It is the size libjpeg decodes:
// a header passes only if each marker stands where the segment before it ended, so its segments are
// the ones libjpeg reads (libjpeg skips bytes between segments, a stuffed FF 00 among them, where a
// walk taking them for a segment reads a frame header libjpeg never does).
Structure check_structure(std::span<const uint8_t> d, FrameSize* size = nullptr);

}  // namespace whiskeye::jpeg
