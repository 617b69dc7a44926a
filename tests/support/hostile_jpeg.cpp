// Hostile JPEG frames built from real ones (see hostile_jpeg.h). Marker codes from ITU-T T.81, B.1.
#include "hostile_jpeg.h"

#include "mjpeg_pattern.h"

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <random>
#include <stdexcept>
#include <string>

// libjpeg's C API, after <cstdio> (it needs FILE).
#include <jpeglib.h>

namespace whiskeye::test {
namespace {

constexpr uint8_t kSOI = 0xd8, kEOI = 0xd9, kSOS = 0xda, kDHT = 0xc4, kAPP1 = 0xe1;

bool is_sof(uint8_t m) { return m >= 0xc0 && m <= 0xcf && m != kDHT && m != 0xc8 && m != 0xcc; }

std::size_t length_at(std::span<const uint8_t> j, std::size_t pos) { return (std::size_t{j[pos + 2]} << 8) | j[pos + 3]; }

void append(std::vector<uint8_t>& out, std::span<const uint8_t> j, const JpegSegment& s) {
  out.insert(out.end(), j.begin() + static_cast<std::ptrdiff_t>(s.begin), j.begin() + static_cast<std::ptrdiff_t>(s.end));
}

// libjpeg reports a fatal error by longjmp; nothing with a destructor lives between setjmp and it.
struct Encoder {
  jpeg_compress_struct cinfo;
  jpeg_error_mgr err;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void on_encoder_error(j_common_ptr c) {
  auto* e = reinterpret_cast<Encoder*>(reinterpret_cast<char*>(c->err) - offsetof(Encoder, err));
  (*c->err->format_message)(c, e->message);
  std::longjmp(e->jump, 1);
}

// Each of the three components in a sequential scan of its own.
const jpeg_scan_info kScanPerComponent[3] = {{1, {0}, 0, 63, 0, 0}, {1, {1}, 0, 63, 0, 0}, {1, {2}, 0, 63, 0, 0}};

struct EncodeOptions {
  int components = 1;                    // 1: grey; 3: RGB in, `colour_space` in the JPEG, 4:4:4
  J_COLOR_SPACE colour_space = JCS_YCbCr;
  int quality = 85;
  bool progressive = false;              // libjpeg's simple progression
  bool arithmetic = false;
  const jpeg_scan_info* scans = nullptr;  // a scan script of `num_scans`
  int num_scans = 0;
  unsigned restart_interval = 0;         // MCUs between restart markers (0: none)
};

// `pixels` (width x height, `o.components` bytes a pixel, no padding) encoded with libjpeg.
std::vector<uint8_t> encode(std::span<const uint8_t> pixels, int width, int height, const EncodeOptions& o) {
  Encoder e;
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  e.cinfo.err = jpeg_std_error(&e.err);
  e.err.error_exit = on_encoder_error;
  jpeg_create_compress(&e.cinfo);
  if (setjmp(e.jump) != 0) {
    jpeg_destroy_compress(&e.cinfo);
    std::free(buffer);
    throw std::runtime_error(std::string("libjpeg: ") + e.message);
  }
  jpeg_mem_dest(&e.cinfo, &buffer, &size);
  e.cinfo.image_width = static_cast<JDIMENSION>(width);
  e.cinfo.image_height = static_cast<JDIMENSION>(height);
  e.cinfo.input_components = o.components;
  e.cinfo.in_color_space = o.components == 3 ? JCS_RGB : JCS_GRAYSCALE;
  jpeg_set_defaults(&e.cinfo);
  if (o.components == 3) {
    jpeg_set_colorspace(&e.cinfo, o.colour_space);
    e.cinfo.comp_info[0].h_samp_factor = e.cinfo.comp_info[0].v_samp_factor = 1;  // 4:4:4
  }
  jpeg_set_quality(&e.cinfo, o.quality, TRUE);
  if (o.progressive) jpeg_simple_progression(&e.cinfo);
  if (o.scans != nullptr) {
    e.cinfo.scan_info = o.scans;
    e.cinfo.num_scans = o.num_scans;
  }
  e.cinfo.arith_code = o.arithmetic ? TRUE : FALSE;
  e.cinfo.restart_interval = o.restart_interval;
  jpeg_start_compress(&e.cinfo, TRUE);
  const std::size_t row_bytes = static_cast<std::size_t>(width) * o.components;
  while (e.cinfo.next_scanline < e.cinfo.image_height) {
    // libjpeg's API takes rows as non-const; it only reads them.
    JSAMPROW row = const_cast<JSAMPROW>(pixels.data() + e.cinfo.next_scanline * row_bytes);
    jpeg_write_scanlines(&e.cinfo, &row, 1);
  }
  jpeg_finish_compress(&e.cinfo);
  jpeg_destroy_compress(&e.cinfo);
  std::vector<uint8_t> jpeg(buffer, buffer + size);
  std::free(buffer);
  return jpeg;
}

}  // namespace

std::vector<JpegSegment> jpeg_segments(std::span<const uint8_t> j) {
  if (j.size() < 4 || j[0] != 0xff || j[1] != kSOI) throw std::runtime_error("jpeg_segments: no start-of-image marker");
  std::vector<JpegSegment> out{{kSOI, 0, 2}};
  std::size_t pos = 2;
  while (true) {
    if (pos + 2 > j.size() || j[pos] != 0xff) throw std::runtime_error("jpeg_segments: no marker at " + std::to_string(pos));
    const uint8_t marker = j[pos + 1];
    if (marker == kEOI) {
      out.push_back({kEOI, pos, pos + 2});
      return out;
    }
    if (pos + 4 > j.size()) throw std::runtime_error("jpeg_segments: cut short");
    std::size_t end = pos + 2 + length_at(j, pos);
    if (marker == kSOS) {
      // Entropy-coded data up to the next marker that is neither a stuffed zero nor a restart marker.
      while (end + 1 < j.size() && !(j[end] == 0xff && j[end + 1] != 0x00 && (j[end + 1] < 0xd0 || j[end + 1] > 0xd7))) {
        end += j[end] == 0xff ? 2 : 1;
      }
    }
    if (end > j.size()) throw std::runtime_error("jpeg_segments: a segment runs past the end");
    out.push_back({marker, pos, end});
    pos = end;
  }
}

std::vector<uint8_t> encode_jpeg_scans(std::span<const uint8_t> grey, int width, int height, int stride,
                                       ScanLayout layout, int quality) {
  const int components = layout == ScanLayout::kScanPerComponent ? 3 : 1;
  std::vector<uint8_t> pixels(static_cast<std::size_t>(width) * height * components);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width * components; ++x) {
      pixels[static_cast<std::size_t>(y) * width * components + x] = grey[static_cast<std::size_t>(y) * stride + x / components];
    }
  }
  EncodeOptions o;
  o.components = components;
  o.quality = quality;
  o.progressive = layout == ScanLayout::kProgressive;
  o.arithmetic = layout == ScanLayout::kArithmetic;
  if (layout == ScanLayout::kScanPerComponent) {
    o.scans = kScanPerComponent;
    o.num_scans = 3;
  }
  return encode(pixels, width, height, o);
}

std::vector<uint8_t> costliest_baseline_jpeg(int width, int height, uint32_t seed) {
  std::vector<uint8_t> noise(static_cast<std::size_t>(width) * height * 3);
  std::mt19937 rng(seed);
  for (uint8_t& p : noise) p = static_cast<uint8_t>(rng());
  EncodeOptions o;
  o.components = 3;
  o.colour_space = JCS_RGB;
  o.quality = 100;
  o.restart_interval = 1;
  return encode(noise, width, height, o);
}

std::vector<uint8_t> with_frame_size(std::vector<uint8_t> jpeg, int width, int height) {
  for (const JpegSegment& s : jpeg_segments(jpeg)) {
    if (!is_sof(s.marker)) continue;
    jpeg[s.begin + 5] = static_cast<uint8_t>(height >> 8);
    jpeg[s.begin + 6] = static_cast<uint8_t>(height);
    jpeg[s.begin + 7] = static_cast<uint8_t>(width >> 8);
    jpeg[s.begin + 8] = static_cast<uint8_t>(width);
    return jpeg;
  }
  throw std::runtime_error("with_frame_size: no frame header");
}

std::vector<uint8_t> hide_frame_behind(std::span<const uint8_t> shown, std::span<const uint8_t> hidden) {
  std::vector<uint8_t> header;  // shown's segments after SOI, up to its first scan
  for (const JpegSegment& s : jpeg_segments(shown)) {
    if (s.marker == kSOS) break;
    if (s.marker != kSOI) append(header, shown, s);
  }
  if (header.size() + 2 > 0xffff) throw std::runtime_error("hide_frame_behind: header too long for an APP1 segment");
  const std::size_t app1 = header.size() + 2;
  // FF 00 and "00 06": a segment of 6 bytes to a walk that takes FF 00 for one, which then lands on
  // shown's header inside the APP1 (at offset 10); libjpeg skips the four bytes up to the APP1.
  const uint8_t start[] = {0xff, kSOI, 0xff, 0x00, 0x00, 0x06, 0xff, kAPP1, static_cast<uint8_t>(app1 >> 8),
                           static_cast<uint8_t>(app1)};
  std::vector<uint8_t> out(sizeof(start) + header.size() + hidden.size() - 2);
  const auto rest = std::copy(header.begin(), header.end(), std::copy(std::begin(start), std::end(start), out.begin()));
  std::copy(hidden.begin() + 2, hidden.end(), rest);
  return out;
}

std::vector<uint8_t> with_repeated_ac_scans(std::span<const uint8_t> progressive, int copies) {
  const std::vector<JpegSegment> segs = jpeg_segments(progressive);
  std::size_t previous_scan = 0;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    if (segs[i].marker != kSOS) continue;
    const std::size_t b = segs[i].begin;
    // One component (FF DA, length, Ns 1, Cs, Td/Ta), then Ss 6, Se 63.
    if (!(progressive[b + 4] == 1 && progressive[b + 7] == 6 && progressive[b + 8] == 63)) {
      previous_scan = i;
      continue;
    }
    std::vector<uint8_t> out(progressive.begin(), progressive.begin() + static_cast<std::ptrdiff_t>(segs.back().begin));
    // Its Huffman table, which a later scan redefined, then the scan as a full-precision first pass.
    for (std::size_t t = previous_scan + 1; t < i; ++t) {
      if (segs[t].marker == kDHT) append(out, progressive, segs[t]);
    }
    std::vector<uint8_t> scan(progressive.begin() + static_cast<std::ptrdiff_t>(b),
                              progressive.begin() + static_cast<std::ptrdiff_t>(segs[i].end));
    scan[9] = 0x00;  // Ah 0, Al 0
    for (int c = 0; c < copies; ++c) out.insert(out.end(), scan.begin(), scan.end());
    append(out, progressive, segs.back());
    return out;
  }
  throw std::runtime_error("with_repeated_ac_scans: no scan of AC coefficients 6-63 (not libjpeg's simple progression)");
}

std::vector<uint8_t> with_repeated_last_scan(std::span<const uint8_t> jpeg, int copies) {
  const std::vector<JpegSegment> segs = jpeg_segments(jpeg);
  const JpegSegment& last = segs[segs.size() - 2];
  if (last.marker != kSOS) throw std::runtime_error("with_repeated_last_scan: the end marker does not follow a scan");
  std::vector<uint8_t> out(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(last.end));
  for (int c = 0; c < copies; ++c) append(out, jpeg, last);
  append(out, jpeg, segs.back());
  return out;
}

std::vector<uint8_t> camera_frame_hiding_progressive(int width, int height, int hidden_width, int hidden_height) {
  const std::vector<uint8_t> flat(64 * 48, 128);
  const std::vector<uint8_t> hidden = encode_jpeg_scans(flat, 64, 48, 64, ScanLayout::kProgressive);
  return hide_frame_behind(mjpeg_pattern_jpeg(width, height, 52), with_frame_size(hidden, hidden_width, hidden_height));
}

std::vector<uint8_t> progressive_with_repeated_scans(int width, int height, int copies) {
  const std::vector<uint8_t> flat(static_cast<std::size_t>(width) * height, 128);
  return with_repeated_ac_scans(encode_jpeg_scans(flat, width, height, width, ScanLayout::kProgressive), copies);
}

}  // namespace whiskeye::test
