// A JPEG's marker structure, read without decoding: the frame size its header claims, whether it
// ends, and whether it is put together as a JPEG at all: camerad refuses a damaged MJPEG frame with
// it before it publishes it, counting it. slamd's decoder reads only ends_with_eoi() here: the size
// it checks is the one libjpeg parsed (a second parser's answer is not the one that counts). Pure;
// no allocation.
#pragma once

#include <cstdint>
#include <span>

namespace whiskeye::jpeg {

struct FrameSize {
  int width = 0, height = 0;
};
// The frame size in the first SOF segment, or {0, 0} when there is none before the first scan.
FrameSize frame_size(std::span<const uint8_t> d);

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
// Linear in the size (one memchr-driven pass over the entropy-coded data).
Structure check_structure(std::span<const uint8_t> d);

}  // namespace whiskeye::jpeg
