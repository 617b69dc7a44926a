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

enum class JpegResult { kOk, kError, kWarning, kWrongSize };

// Decodes `data` as greyscale into `out` (width x height, `stride` bytes per row).
JpegResult decode_jpeg_grey(JpegDecoder* d, const uint8_t* data, std::size_t size, uint8_t* out, std::size_t stride,
                            int width, int height) {
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
  jpeg_mem_src(&d->cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&d->cinfo, TRUE);
  d->cinfo.out_color_space = JCS_GRAYSCALE;
  jpeg_start_decompress(&d->cinfo);
  if (static_cast<int>(d->cinfo.output_width) != width || static_cast<int>(d->cinfo.output_height) != height ||
      d->cinfo.output_components != 1) {
    jpeg_destroy_decompress(&d->cinfo);
    return JpegResult::kWrongSize;
  }
  while (d->cinfo.output_scanline < d->cinfo.output_height) {
    JSAMPROW row = out + static_cast<std::size_t>(d->cinfo.output_scanline) * stride;
    jpeg_read_scanlines(&d->cinfo, &row, 1);
  }
  jpeg_finish_decompress(&d->cinfo);
  const bool warned = d->err.num_warnings > 0;
  jpeg_destroy_decompress(&d->cinfo);
  return warned ? JpegResult::kWarning : JpegResult::kOk;
}

// Decoding costs what the header claims, not what the message weighs: a 331-byte JPEG claiming
// 10000 x 10000 took 2 s and 550 MB. No camera of this robot comes near 16.8 MP.
constexpr int64_t kMaxJpegPixels = int64_t{4096} * 4096;

}  // namespace

void check_mjpeg_frame(std::span<const uint8_t> jpeg, int width, int height) {
  if (jpeg.empty()) throw InputError("image: empty MJPEG frame");
  // cv::imdecode took the size from the header, not from the message: a few hundred bytes can
  // claim 32752 x 32752 pixels (gigabytes, seconds of CPU), so the header is read first.
  const auto [header_width, header_height] = jpeg::frame_size(jpeg);
  if (header_width == 0 || header_height == 0) {
    throw InputError("image: MJPEG frame without a readable JPEG frame header");
  }
  if (header_width != width || header_height != height) {
    throw InputError("image: MJPEG frame is " + std::to_string(header_width) + "x" + std::to_string(header_height) +
                     " by its JPEG header, the message says " + std::to_string(width) + "x" +
                     std::to_string(height));
  }
  if (int64_t{width} * height > kMaxJpegPixels) {
    throw InputError("image: MJPEG frame of " + std::to_string(width) + "x" + std::to_string(height) +
                     " is larger than 4096x4096 pixels");
  }
  // A frame cut off in transfer has no end marker; OpenCV would decode it anyway, greying out what
  // is missing, and that grey would become a template.
  if (!jpeg::ends_with_eoi(jpeg)) throw InputError("image: MJPEG frame cut off (no end-of-image marker)");
}

void decode_mjpeg_grey(std::span<const uint8_t> jpeg, int width, int height, uint8_t* out, std::size_t stride) {
  check_mjpeg_frame(jpeg, width, height);
  JpegDecoder decoder;
  switch (decode_jpeg_grey(&decoder, jpeg.data(), jpeg.size(), out, stride, width, height)) {
    case JpegResult::kOk: return;
    case JpegResult::kError: throw InputError(std::string("image: MJPEG frame does not decode: ") + decoder.error);
    case JpegResult::kWarning: throw InputError(std::string("image: MJPEG frame is damaged (") + decoder.warning + ")");
    case JpegResult::kWrongSize: throw InputError("image: MJPEG frame decodes to another size than its header's");
  }
  throw InputError("image: MJPEG frame does not decode");
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
