// Reading a JSON document from a file with errors that name it.
#pragma once

#include <string>

#include <nlohmann/json_fwd.hpp>

#include "core/status.h"

namespace hairrig {

// NotFound when the file cannot be opened (the message adds `hint`, what to
// do about it); CorruptData when it is not valid JSON.
Result<nlohmann::json> ReadJsonFile(const std::string& path, const std::string& hint = "");

}  // namespace hairrig
