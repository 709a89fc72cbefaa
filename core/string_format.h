// printf-style formatting into a std::string, for the summaries' brief
// reports: the compiler checks the format against the arguments.
#pragma once

#include <cstdarg>
#include <cstdio>
#include <string>

namespace hairrig {

[[gnu::format(printf, 1, 2)]] inline std::string StringPrintf(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list measure;
  va_copy(measure, args);
  const int size = std::vsnprintf(nullptr, 0, format, measure);
  va_end(measure);
  std::string text(size > 0 ? static_cast<size_t>(size) : 0, '\0');
  if (size > 0) std::vsnprintf(text.data(), text.size() + 1, format, args);
  va_end(args);
  return text;
}

}  // namespace hairrig
