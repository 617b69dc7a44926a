// JPEG marker structure (see jpeg_markers.h). Marker codes from ITU-T T.81, table B.1.
#include "whiskeye/common/jpeg_markers.h"

#include <cstring>

namespace whiskeye::jpeg {
namespace {

constexpr uint8_t kSOI = 0xd8, kEOI = 0xd9, kSOS = 0xda;

bool is_sof(uint8_t m) { return m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc; }
// Markers followed by a length field that may stand between segments: SOFn, DHT, DAC, SOS, DQT, DNL,
// DRI, DHP, EXP, APPn, COM. (C8 and F0-FD are reserved, 01-BF and RSTn belong to no segment.)
bool is_segment(uint8_t m) { return (m >= 0xc0 && m <= 0xcf && m != 0xc8) || (m >= 0xda && m <= 0xef) || m == 0xfe; }

std::size_t end_without_padding(std::span<const uint8_t> d) {
  std::size_t end = d.size();
  while (end > 0 && d[end - 1] == 0x00) --end;
  return end;
}

}  // namespace

bool ends_with_eoi(std::span<const uint8_t> d) {
  const std::size_t end = end_without_padding(d);
  return end >= 2 && d[end - 2] == 0xff && d[end - 1] == kEOI;
}

const char* structure_name(Structure s) {
  switch (s) {
    case Structure::kWhole: return "a whole JPEG";
    case Structure::kNoStartMarker: return "not a JPEG (no start-of-image marker)";
    case Structure::kBadHeader: return "a JPEG whose header does not parse";
    case Structure::kCutShort: return "a JPEG cut short (no end-of-image marker)";
    case Structure::kDamagedData: return "a JPEG with damaged data after its header";
  }
  return "?";
}

Structure check_structure(std::span<const uint8_t> d, FrameSize* size) {
  if (size != nullptr) *size = {};
  if (d.size() < 2 || d[0] != 0xff || d[1] != kSOI) return Structure::kNoStartMarker;
  if (!ends_with_eoi(d)) return Structure::kCutShort;
  const std::size_t end = end_without_padding(d);  // d[end - 2], d[end - 1] are FF D9
  bool have_frame = false, in_scans = false;
  FrameSize frame;
  // Any failure once the first scan has begun is damage to the data, not to the header.
  const auto bad = [&] { return in_scans ? Structure::kDamagedData : Structure::kBadHeader; };
  std::size_t pos = 2;
  while (pos < end) {
    // Between segments: a marker, after any number of fill bytes (FF).
    if (d[pos] != 0xff) return bad();
    while (pos + 1 < end && d[pos + 1] == 0xff) ++pos;
    if (pos + 1 >= end) return bad();
    const uint8_t marker = d[pos + 1];
    if (marker == kEOI) {
      if (pos + 2 != end || !in_scans) return bad();
      if (size != nullptr) *size = frame;
      return Structure::kWhole;
    }
    if (!is_segment(marker) || pos + 4 > end) return bad();
    const std::size_t length = (std::size_t{d[pos + 2]} << 8) | d[pos + 3];
    if (length < 2 || pos + 2 + length > end) return bad();
    if (is_sof(marker) && !have_frame) {
      if (length < 7) return bad();
      frame = {(d[pos + 7] << 8) | d[pos + 8], (d[pos + 5] << 8) | d[pos + 6]};
      have_frame = true;
    }
    pos += 2 + length;
    if (marker != kSOS) continue;
    if (!have_frame) return Structure::kBadHeader;
    in_scans = true;
    // Entropy-coded data: an FF is a stuffed FF 00, a restart marker, a fill byte before a marker, or
    // the marker that ends the scan.
    while (true) {
      const void* ff = std::memchr(d.data() + pos, 0xff, end - pos);
      if (ff == nullptr) return Structure::kDamagedData;  // the scan's segment ran over the EOI
      pos = static_cast<std::size_t>(static_cast<const uint8_t*>(ff) - d.data());  // at most end - 2, the EOI's
      const uint8_t next = d[pos + 1];
      if (next == 0x00 || (next >= 0xd0 && next <= 0xd7)) {
        pos += 2;
      } else if (next == 0xff) {
        ++pos;
      } else {
        break;  // a marker: back to the segment loop
      }
    }
  }
  return bad();
}

}  // namespace whiskeye::jpeg
