// JPEG frames a hostile sender could put in a CAMERA message, built in code from frames of the
// project's own encoders (mjpeg_pattern.h; libjpeg for the scan layouts no camera sends) by splicing
// markers and segments: the probes of docs/reliability.md ("Hostile input, round 3: camera frames").
// Used by the tests of slamd's MJPEG decoder, of its callers and of camerad's MJPEG check, by the
// decode benchmark and for the fuzz seeds (fuzz_make_seeds).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace whiskeye::test {

// A JPEG's segments in order, from SOI to EOI: each is a marker with what follows it; a scan (SOS)
// runs to the end of its entropy-coded data. Throws std::runtime_error on a JPEG that does not parse.
struct JpegSegment {
  uint8_t marker = 0;
  std::size_t begin = 0, end = 0;  // [begin, end) in the JPEG, the marker's FF included
};
std::vector<JpegSegment> jpeg_segments(std::span<const uint8_t> jpeg);

// A grey image (width x height, `stride` bytes a row) encoded with scans no UVC camera sends.
enum class ScanLayout {
  kProgressive,        // libjpeg's simple progression: 6 scans of spectral selection and refinement
  kScanPerComponent,   // sequential (SOF0), YCbCr 4:4:4 with each component in a scan of its own
  kArithmetic,         // sequential, one scan, arithmetic-coded (SOF9)
};
std::vector<uint8_t> encode_jpeg_scans(std::span<const uint8_t> grey, int width, int height, int stride,
                                       ScanLayout layout, int quality = 85);

// The baseline frame that costs the decoder most per pixel of those it takes (docs/performance.md,
// "### MJPEG decode"): noise, independent in each component, encoded RGB (a YCbCr frame's chroma is
// not transformed for grey output, an RGB frame's three components are, and converted), 4:4:4,
// quality 100, a restart marker after every MCU.
std::vector<uint8_t> costliest_baseline_jpeg(int width, int height, uint32_t seed);

// The frame header (SOF) of `jpeg` made to claim width x height; the data stays as it was (a larger
// claim runs out of data, which libjpeg decodes as grey with a warning).
std::vector<uint8_t> with_frame_size(std::vector<uint8_t> jpeg, int width, int height);

// `hidden` behind the header of `shown`, so that a marker walk taking `FF 00` for a segment (as
// jpeg::frame_size did) reads shown's frame header, while libjpeg skips FF 00 (a stuffed zero outside
// a scan: "extraneous bytes"), then an APP1 segment holding shown's header, and reads hidden's.
std::vector<uint8_t> hide_frame_behind(std::span<const uint8_t> shown, std::span<const uint8_t> hidden);

// A progressive frame (ScanLayout::kProgressive) with `copies` more scans of its AC coefficients
// 6-63 after its own, each a first pass at full precision (Al 0): libjpeg's progression checks let
// such a scan follow any other, so it decodes them all, each over every block, without a warning.
// Its own scans first so that the image is whole; a flat image keeps each copy to ~35 bytes.
std::vector<uint8_t> with_repeated_ac_scans(std::span<const uint8_t> progressive, int copies);

// `jpeg` with `copies` more copies of its last scan before the end marker.
std::vector<uint8_t> with_repeated_last_scan(std::span<const uint8_t> jpeg, int copies);

// The probes of docs/reliability.md ("Hostile input, round 3"), as the tests, the benchmark and the
// fuzz seeds use them:
// a width x height camera frame (mjpeg_pattern_jpeg) hiding (hide_frame_behind) a progressive grey
// frame whose header claims hidden_width x hidden_height (its data runs out at once). 32000 x 32000:
// 905 bytes, for which libjpeg's whole-image coefficient buffer is 2 GB.
std::vector<uint8_t> camera_frame_hiding_progressive(int width, int height, int hidden_width, int hidden_height);
// a flat grey width x height progressive frame with `copies` repeated AC scans (with_repeated_ac_scans).
std::vector<uint8_t> progressive_with_repeated_scans(int width, int height, int copies);

}  // namespace whiskeye::test
