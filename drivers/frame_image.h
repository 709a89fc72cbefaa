// A camera's frame as an image: what the capture dataset stores and what the
// operator console's live view shows.
#pragma once

#include <opencv2/core/mat.hpp>

#include "core/status.h"
#include "drivers/camera.h"

namespace hairrig {

// The frame's pixels, owned by the returned image: an encoded frame decoded
// (8-bit BGR, or as the file holds them), RGB8 as BGR, BGR8, Mono8 and
// BayerRG8 (the raw mosaic) as one or three 8-bit channels. CorruptData saying
// what is wrong (the caller names the camera): an encoded frame that does not
// decode, a raw frame whose byte count does not match its geometry and format.
Result<cv::Mat> FrameImage(const Frame& frame);

}  // namespace hairrig
