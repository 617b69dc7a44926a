// slamd's MJPEG decoder (see mjpeg_decode.h), over libjpeg's C API (libjpeg-turbo in Debian).
#include "whiskeye/slamd/mjpeg_decode.h"

#include <whiskeye/common/jpeg_markers.h>

#include <csetjmp>
#include <cstdio>
#include <string>

// libjpeg's C API, after <cstdio> (it needs FILE).
#include <jpeglib.h>

namespace whiskeye::slamd {

using slam::InputError;

namespace {

// Decoding costs what the header claims, not what the message weighs: a 331-byte JPEG claiming
// 10000 x 10000 took 2 s and 550 MB. No camera of this robot comes near 16.8 MP.
constexpr int64_t kMaxJpegPixels = int64_t{4096} * 4096;

// libjpeg's bound on its whole-image buffers (max_memory_to_use): libjpeg-turbo 2.1 applies it to
// those only (a larger one fails with "Backing store not supported"), not to its tables and row
// buffers. A frame decoded here never needs one (see check_header); a backstop should that change:
// the coefficients of the largest grey image.
constexpr long kMaxJpegBufferBytes = static_cast<long>(kMaxJpegPixels * sizeof(JCOEF));

// What libjpeg read in the frame's header (jpeg_read_header, up to the first scan), i.e. what it
// would decode: the one parse whose answer is checked.
struct JpegHeader {
  int width = 0, height = 0;
  bool progressive = false, arithmetic = false;
  int components = 0, components_in_first_scan = 0;
};

// What a frame's header must be for the decode to cost at most one pass over the frame's pixels and
// bytes: the message's size, at most kMaxJpegPixels, and baseline as a camera sends it (sequential,
// Huffman-coded, every component in its one scan). A progressive or multi-scan file is decoded into
// a whole-image buffer (2 bytes a pixel and component) that jpeg_start_decompress allocates and fills
// from every scan before the first row comes out, however many scans: a 905-byte frame hiding a
// 32000 x 32000 progressive header costs 2 GB there, 15,000 scans of 35 bytes 18 s at 4096 x 4096.
// In a file whose first scan holds every component libjpeg refuses a second scan itself ("Didn't
// expect more than one scan").
enum class HeaderCheck { kOk, kWrongSize, kTooLarge, kProgressive, kArithmetic, kScans };

HeaderCheck check_header(const JpegHeader& h, int width, int height) {
  if (h.width != width || h.height != height) return HeaderCheck::kWrongSize;
  if (int64_t{width} * height > kMaxJpegPixels) return HeaderCheck::kTooLarge;
  if (h.progressive) return HeaderCheck::kProgressive;
  if (h.arithmetic) return HeaderCheck::kArithmetic;
  if (h.components_in_first_scan != h.components) return HeaderCheck::kScans;
  return HeaderCheck::kOk;
}

std::string header_refusal(HeaderCheck c, const JpegHeader& h, int width, int height) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  const char* const kBaseline = "; only baseline JPEG (one sequential, Huffman-coded scan) is decoded, as a camera sends it";
  switch (c) {
    case HeaderCheck::kOk: break;
    case HeaderCheck::kWrongSize:
      return "image: MJPEG frame is " + std::to_string(h.width) + "x" + std::to_string(h.height) +
             " by its JPEG header, the message says " + size;
    case HeaderCheck::kTooLarge: return "image: MJPEG frame of " + size + " is larger than 4096x4096 pixels";
    case HeaderCheck::kProgressive: return "image: MJPEG frame is a progressive JPEG" + std::string(kBaseline);
    case HeaderCheck::kArithmetic: return "image: MJPEG frame is arithmetic-coded" + std::string(kBaseline);
    case HeaderCheck::kScans:
      return "image: MJPEG frame has its " + std::to_string(h.components) + " components in several scans (" +
             std::to_string(h.components_in_first_scan) + " in the first)" + kBaseline;
  }
  return "image: MJPEG frame refused";
}

// MJPEG frames are decoded with libjpeg directly (as OpenCV's imdecode does underneath) so that its
// warnings are seen: a frame cut short in transfer with an end-of-image marker appended decodes
// "successfully", greyed out where data is missing, with only libjpeg's own unprefixed "Corrupt JPEG
// data: premature end of data segment" on stderr. Here any warning refuses the frame, with libjpeg's
// text in the reason, and nothing is written to stderr. The state is plain C data: libjpeg reports
// fatal errors by longjmp, which must not cross objects with destructors.
struct JpegDecoder {
  jpeg_decompress_struct cinfo;
  jpeg_error_mgr err;
  std::jmp_buf jump;
  char error[JMSG_LENGTH_MAX];
  char warning[JMSG_LENGTH_MAX];
  JpegHeader header;
  HeaderCheck check = HeaderCheck::kOk;
};

void jpeg_on_error(j_common_ptr c) {
  auto* d = reinterpret_cast<JpegDecoder*>(reinterpret_cast<char*>(c->err) - offsetof(JpegDecoder, err));
  (*c->err->format_message)(c, d->error);
  std::longjmp(d->jump, 1);
}

void jpeg_on_message(j_common_ptr c, int level) {
  if (level >= 0) return;  // trace messages
  auto* d = reinterpret_cast<JpegDecoder*>(reinterpret_cast<char*>(c->err) - offsetof(JpegDecoder, err));
  if (c->err->num_warnings++ == 0) (*c->err->format_message)(c, d->warning);
}

void jpeg_no_output(j_common_ptr) {}

enum class JpegResult { kOk, kError, kWarning, kRefused, kWrongOutput };

// Reads `jpeg`'s header with libjpeg into d->header and checks it (d->check); then, with `out`,
// decodes the frame as greyscale into `out` (width x height, `stride` bytes per row). Without `out`
// only the header is read: libjpeg allocates its tables, nothing the size of the image.
JpegResult run_libjpeg(JpegDecoder* d, std::span<const uint8_t> jpeg, int width, int height, uint8_t* out,
                       std::size_t stride) {
  d->error[0] = d->warning[0] = '\0';
  d->cinfo.err = jpeg_std_error(&d->err);
  d->err.error_exit = jpeg_on_error;
  d->err.emit_message = jpeg_on_message;
  d->err.output_message = jpeg_no_output;
  jpeg_create_decompress(&d->cinfo);
  if (setjmp(d->jump) != 0) {
    jpeg_destroy_decompress(&d->cinfo);
    return JpegResult::kError;
  }
  d->cinfo.mem->max_memory_to_use = kMaxJpegBufferBytes;
  jpeg_mem_src(&d->cinfo, jpeg.data(), static_cast<unsigned long>(jpeg.size()));
  jpeg_read_header(&d->cinfo, TRUE);
  d->header.width = static_cast<int>(d->cinfo.image_width);
  d->header.height = static_cast<int>(d->cinfo.image_height);
  d->header.progressive = d->cinfo.progressive_mode != 0;
  d->header.arithmetic = d->cinfo.arith_code != 0;
  d->header.components = d->cinfo.num_components;
  d->header.components_in_first_scan = d->cinfo.comps_in_scan;
  d->check = check_header(d->header, width, height);
  JpegResult result = JpegResult::kOk;
  if (d->check != HeaderCheck::kOk) {
    result = JpegResult::kRefused;
  } else if (d->err.num_warnings > 0) {
    result = JpegResult::kWarning;
  } else if (out != nullptr) {
    d->cinfo.out_color_space = JCS_GRAYSCALE;
    jpeg_start_decompress(&d->cinfo);
    if (static_cast<int>(d->cinfo.output_width) != width || static_cast<int>(d->cinfo.output_height) != height ||
        d->cinfo.output_components != 1) {
      jpeg_destroy_decompress(&d->cinfo);
      return JpegResult::kWrongOutput;
    }
    while (d->cinfo.output_scanline < d->cinfo.output_height) {
      JSAMPROW row = out + static_cast<std::size_t>(d->cinfo.output_scanline) * stride;
      jpeg_read_scanlines(&d->cinfo, &row, 1);
    }
    jpeg_finish_decompress(&d->cinfo);
    if (d->err.num_warnings > 0) result = JpegResult::kWarning;
  }
  jpeg_destroy_decompress(&d->cinfo);
  return result;
}

// Checks `jpeg` and, with `out`, decodes it (run_libjpeg); throws InputError naming what was wrong.
void read_mjpeg(std::span<const uint8_t> jpeg, int width, int height, uint8_t* out, std::size_t stride) {
  if (jpeg.empty()) throw InputError("image: empty MJPEG frame");
  // A frame cut off in transfer has no end marker; libjpeg would decode it anyway, greying out what
  // is missing, with a warning only once it ran out of data.
  if (!jpeg::ends_with_eoi(jpeg)) throw InputError("image: MJPEG frame cut off (no end-of-image marker)");
  JpegDecoder decoder;
  switch (run_libjpeg(&decoder, jpeg, width, height, out, stride)) {
    case JpegResult::kOk: return;
    case JpegResult::kError: throw InputError(std::string("image: MJPEG frame does not decode: ") + decoder.error);
    case JpegResult::kWarning: throw InputError(std::string("image: MJPEG frame is damaged (") + decoder.warning + ")");
    case JpegResult::kRefused: throw InputError(header_refusal(decoder.check, decoder.header, width, height));
    case JpegResult::kWrongOutput: throw InputError("image: MJPEG frame decodes to another size than its header's");
  }
  throw InputError("image: MJPEG frame does not decode");
}

}  // namespace

void check_mjpeg_frame(std::span<const uint8_t> jpeg, int width, int height) {
  read_mjpeg(jpeg, width, height, nullptr, 0);
}

void decode_mjpeg_grey(std::span<const uint8_t> jpeg, int width, int height, uint8_t* out, std::size_t stride) {
  read_mjpeg(jpeg, width, height, out, stride);
}

slam::FrameDecoder mjpeg_decoder() {
  slam::FrameDecoder d;
  d.pixelformat = slam::kPixMjpeg;
  d.check = [](const slam::ImageView& f) { check_mjpeg_frame(f.data, f.width, f.height); };
  d.decode = [](const slam::ImageView& f, uint8_t* out, std::size_t stride) {
    decode_mjpeg_grey(f.data, f.width, f.height, out, stride);
  };
  return d;
}

}  // namespace whiskeye::slamd
