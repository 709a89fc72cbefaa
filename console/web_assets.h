// The console's page (console/web/), built into the binary so that it is
// served offline with no files beside the executable.
#pragma once

#include <cstddef>
#include <vector>

namespace hairrig {

struct EmbeddedFile {
  const char* path;  // relative to console/web/: "index.html", "app.js"
  const unsigned char* data;
  size_t size;
};

const std::vector<EmbeddedFile>& ConsoleWebAssets();

}  // namespace hairrig
