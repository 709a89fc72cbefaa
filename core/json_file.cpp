#include "core/json_file.h"

#include <fstream>

#include <nlohmann/json.hpp>

namespace hairrig {

Result<nlohmann::json> ReadJsonFile(const std::string& path, const std::string& hint) {
  std::ifstream in(path);
  if (!in) return NotFound(path + ": cannot be opened" + (hint.empty() ? "" : "; " + hint));
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) return CorruptData(path + ": not valid JSON");
  return j;
}

}  // namespace hairrig
