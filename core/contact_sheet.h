// A contact sheet: thumbnails of a set of images in a grid, each labelled.
#pragma once

#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

namespace hairrig {

// 8-bit BGR `images` in a grid of `columns` per row, each `thumb_width_px`
// wide at the first image's aspect ratio, with its label (if any) on a black
// band at its top, on a dark grey ground; empty when `images` is.
cv::Mat MakeContactSheet(const std::vector<cv::Mat>& images, const std::vector<std::string>& labels,
                         int columns, int thumb_width_px);

}  // namespace hairrig
