// slamd's MJPEG decoder, at the daemon's edge (the SLAM core holds no image codec): one camera frame
// (a JPEG) to 8-bit grey, refusing a damaged one with a reason instead of decoding it to grey.
// SlamNode gives it to the core as its FrameDecoder (mjpeg_decoder()), so make_visual_template reads
// MJPEG frames; the viewer shows frames with it, the VM test of camerad's MJPEG path decodes the
// published frames with it too, and bench/slamd_core/bench_mjpeg.cpp measures it against
// cv::imdecode and libturbojpeg.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "whiskeye/slam/types.h"
#include "whiskeye/slam/visual_template.h"

namespace whiskeye::slamd {

// What is checked before decoding, allocating only libjpeg's tables (so the caller may allocate
// `out` after it). libjpeg reads the header (jpeg_read_header: the one parse whose answer counts, the
// header libjpeg will decode), which must give the message's size (`width` x `height`), at most
// 4096 x 4096 (decoding costs what the header claims), and baseline JPEG as a camera sends it: one
// sequential, Huffman-coded scan holding every component (a progressive or multi-scan frame is
// decoded into a whole-image buffer from all its scans, however many, before its first row). Any
// warning of libjpeg's while reading the header refuses the frame too, and the frame must end with
// its end-of-image marker. Throws InputError ("image: MJPEG frame ...").
void check_mjpeg_frame(std::span<const uint8_t> jpeg, int width, int height);

// Decodes `jpeg` to grey into `out` (`stride` bytes a row, `height` rows), after the checks of
// check_mjpeg_frame() on the header it decodes. Any warning of libjpeg's refuses the frame (a frame
// cut short with an EOI appended decodes "successfully", greyed out where data is missing), with
// libjpeg's words in the reason; libjpeg writes nothing to stderr. Costs one pass over the frame's
// pixels and bytes. Throws InputError ("image: MJPEG frame ...").
void decode_mjpeg_grey(std::span<const uint8_t> jpeg, int width, int height, uint8_t* out, std::size_t stride);

// The two above as the SLAM core's decoder of kPixMjpeg frames.
slam::FrameDecoder mjpeg_decoder();

}  // namespace whiskeye::slamd
