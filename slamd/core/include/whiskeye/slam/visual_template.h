// Visual template (paper Fig. 2 / Algorithm 1 "visual process"): greyscale (a compressed frame
// decoded by the injected FrameDecoder) → crop →
// block-average subsample → normalise. The result is stored compactly as one byte per pixel
// (intensity in [0, 1] quantised to 0..255), which is what the matcher compares.
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/slam/types.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace whiskeye::slam {

struct VisualParams {
  // Crop rectangle in source pixels; width/height 0 = to the image edge. The original ViTa-SLAM
  // kept the upper 640×300 of the 640×480 frame (the floor carries no place information).
  int crop_x = 0;
  int crop_y = 0;
  int crop_width = 640;
  int crop_height = 300;
  int template_width = 64;
  int template_height = 40;
  // Global normalisation v·N/mean, clamped to [0, 1]; 0 = off (OpenRatSLAM's vt_normalisation).
  double global_normalisation = 0.4;
  // Patch normalisation: each pixel minus the mean over a (2k+1)² patch, divided by the patch's
  // standard deviation, mapped back to [0, 1] as 0.5 + z/6 (clamped). 0 = off.
  int patch_radius = 0;
};
void load(const ParamNode& node, VisualParams& p);

struct VisualTemplate {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;  // row-major, width·height
  float mean = 0.0f;            // mean intensity in [0, 1] (for the matcher's prefilter)
};

// A compressed pixel format (MJPEG) is not decoded by the core, which holds no image codec: the
// daemon's edge injects a decoder for it (slamd: slamd::mjpeg_decoder(), whiskeye/slamd/mjpeg_decode.h).
struct FrameDecoder {
  uint32_t pixelformat = 0;  // the format it decodes
  // Refuses a frame (InputError) before anything is allocated for what it claims.
  std::function<void(const ImageView& frame)> check;
  // Decodes a checked frame to 8-bit grey into `out` (`stride` bytes a row, frame.height rows);
  // throws InputError.
  std::function<void(const ImageView& frame, uint8_t* out, std::size_t stride)> decode;
};

// Throws InputError naming the problem (size/stride/data length mismatch, unknown FourCC, a frame
// `decoder` refuses, empty crop). `decoder`: for its compressed format, else none.
VisualTemplate make_visual_template(const ImageView& image, const VisualParams& params,
                                    const FrameDecoder* decoder = nullptr);

// The part of `image` make_visual_template reads with `params`: of an uncompressed image, its rows
// down to the crop's bottom one (the same image with fewer rows, which gives the same template); a
// compressed one, one whose data is short or whose crop lies outside it whole (the same error, with
// the image's size). A replay reads only these bytes of a frame from the log.
ImageView visual_rows(const ImageView& image, const VisualParams& params);

// Shrinks a width × height float image (`stride_floats` between rows) into out_width × out_height
// floats at `out` by area averaging, with the floats cv::resize(INTER_AREA) gives bit for bit; a
// shrink by a non-integer factor (slam.yaml's 7.5 rows a template row) is computed here, row by
// row, at a fraction of OpenCV's cost, every other case by cv::resize.
void area_shrink(const float* grey, int width, int height, int stride_floats, float* out, int out_width,
                 int out_height);

// From an already greyscale float image in [0, 1] (tests, and the path every format ends in).
VisualTemplate make_visual_template_from_grey(const float* grey, int width, int height, int stride_floats,
                                              const VisualParams& params);

}  // namespace whiskeye::slam
