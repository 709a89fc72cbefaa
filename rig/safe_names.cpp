#include "rig/safe_names.h"

#include <cctype>
#include <cstdio>

namespace hairrig {
namespace {

bool IsPlainNameChar(unsigned char c) {
  return std::isalnum(c) || c == '-' || c == '_' || c == '.';
}

std::string Printable(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

}  // namespace

Result<std::string> SubjectFolderName(const std::string& subject) {
  const std::string shown = "subject name '" + Printable(subject) + "'";
  if (subject.empty()) return InvalidArgument("the subject name is empty");
  if (subject.size() > 100) return InvalidArgument(shown + " is longer than 100 characters");
  std::string out;
  for (unsigned char c : subject) {
    if (c < 0x20 || c == 0x7f) return InvalidArgument(shown + " contains a control character");
    if (c == '/' || c == '\\') {
      return InvalidArgument(shown +
                             " contains a path separator: give a plain name such as 'wig_03'");
    }
    if (c == ' ') {
      out += '_';
    } else if (IsPlainNameChar(c)) {
      out += static_cast<char>(c);
    } else {
      return InvalidArgument(shown + " contains '" + std::string(1, static_cast<char>(c)) +
                             "': use letters, digits, spaces, '-', '_' and '.'");
    }
  }
  if (out[0] == '.')
    return InvalidArgument(shown + " starts with '.': it would be hidden or mean a parent folder");
  return out;
}

std::string FileNamePart(const std::string& text) {
  std::string out;
  for (unsigned char c : text) out += IsPlainNameChar(c) ? static_cast<char>(c) : '_';
  if (out.empty()) return "_";
  if (out[0] == '.') out[0] = '_';
  return out;
}

}  // namespace hairrig
