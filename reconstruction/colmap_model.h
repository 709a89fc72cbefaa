// Reads a COLMAP text model (cameras.txt, images.txt; colmap.github.io/format.html)
// as reconstruction views, so that captures of other rigs can be reconstructed.
//
// Camera models: PINHOLE (fx fy cx cy), SIMPLE_RADIAL (f cx cy k), RADIAL
// (f cx cy k1 k2), OPENCV (fx fy cx cy k1 k2 p1 p2) and FULL_OPENCV with k4 = k5 =
// k6 = 0 (the rational terms this project's lens model lacks). COLMAP's pixel
// convention puts (0.5, 0.5) at the centre of the top-left pixel; the views
// use this project's (0, 0), so principal points move by -0.5 px.
// Poses: QW QX QY QZ TX TY TZ is cam_from_world, in the model's units (mm
// for models written by `hairrig calibrate`).
#pragma once

#include <string>

#include "core/status.h"
#include "reconstruction/views.h"

namespace hairrig {

struct ColmapReadOptions {
  std::string images_dir;  // where NAME of images.txt is found (required)
  std::string
      masks_dir;  // optional: <masks_dir>/<NAME>.png (COLMAP's own convention) or <stem>.png

  // InvalidArgument naming images_dir when it is empty.
  Status Check() const;
};

// Nothing outside `images_dir` (and `masks_dir`) is read: a NAME that is
// absolute, has a '..' component or leads out through a symlink is refused,
// as is an image file that is not a regular file (a FIFO, a device), not an
// image (core/image_file.h: PNG, JPEG, TIFF, BMP, PNM, WebP) or claims more
// than kMaxImagePixels; the error names images.txt, the line and the NAME.
// Only headers are read here; the views' images are decoded later, from
// their image_path and mask_path: the files' paths with symlinks resolved.
// A repeated CAMERA_ID in cameras.txt, a repeated IMAGE_ID or NAME in
// images.txt, or two NAMEs with the same view name (the file name without its
// extension, which names the files written for the view) is CorruptData naming
// the line and the one it repeats. Both files are read only if they are regular
// files of at most kMaxFileBytes (core/file_util.h).
//
// InvalidArgument for bad options (ColmapReadOptions::Check). CorruptData
// naming the file and line for a malformed line, an unknown
// camera model, a non-finite or out-of-range number, or an image whose camera
// is not listed; NotFound for a missing file. An image whose file is missing is
// left out with its reason (ReconstructionInput::left_out); no image left is
// an error.
Result<ReconstructionInput> ReadColmapModel(const std::string& model_dir,
                                            const ColmapReadOptions& options);

}  // namespace hairrig
