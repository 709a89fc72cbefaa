#include "sim_hw/tag_texture.h"

#include <cstdlib>
#include <memory>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
}

namespace hairrig {

Result<TagPattern> MakeTagPattern(const std::string& family, int id) {
  if (family != "tag36h11")
    return InvalidArgument("tag family '" + family + "' is not supported (use tag36h11)");
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> fam(tag36h11_create(),
                                                                       tag36h11_destroy);
  if (id < 0 || static_cast<uint32_t>(id) >= fam->ncodes) {
    return NotFound("tag36h11 has no tag id " + std::to_string(id) + " (ids 0-" +
                    std::to_string(fam->ncodes - 1) + ")");
  }
  image_u8_t* image = apriltag_to_image(fam.get(), id);
  if (image == nullptr) return Internal("libapriltag could not draw tag " + std::to_string(id));
  TagPattern pattern;
  pattern.width = image->width;
  pattern.white.resize(static_cast<size_t>(image->width * image->height));
  for (int row = 0; row < image->height; ++row) {
    for (int col = 0; col < image->width; ++col) {
      pattern.white[static_cast<size_t>(row * image->width + col)] =
          image->buf[row * image->stride + col] > 127;
    }
  }
  // Debian's libapriltag does not export image_u8_destroy: free what
  // image_u8_create allocated (the pixel buffer and the struct) ourselves.
  std::free(image->buf);
  std::free(image);
  return pattern;
}

}  // namespace hairrig
