// Test helper shared by the batch module's tests.
#pragma once

#include <fstream>
#include <iterator>
#include <string>

namespace hairrig {

// The whole text of `path`; empty when it cannot be read.
inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace hairrig
