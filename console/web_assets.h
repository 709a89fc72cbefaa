// The console's page (console/web/) and the three.js modules its 3D view
// imports, built into the binary so that they are served offline with no
// files beside the executable.
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

// three.js for the page's 3D view (Debian's libjs-three), paths relative to
// /usr/share/javascript: "three/build/three.module.js", served under /vendor/.
const std::vector<EmbeddedFile>& ConsoleVendorAssets();

}  // namespace hairrig
