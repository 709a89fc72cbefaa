// Names that become files and folders of a capture. Anything a user or a
// device supplies (a subject name, a camera serial) passes through here before
// it touches the file system, so nothing is written outside the capture folder.
#pragma once

#include <string>

#include "core/status.h"

namespace hairrig {

// A subject name as a folder name: letters, digits, '-', '_' and '.' are kept,
// spaces become '_'. Refused (InvalidArgument saying why): empty, longer than
// 100 bytes, leading '.', path separators, control characters, anything else.
Result<std::string> SubjectFolderName(const std::string& subject);

// A device-supplied text (a camera serial) as part of a file name: every byte
// outside [A-Za-z0-9._-] becomes '_', a leading '.' too; never empty.
std::string FileNamePart(const std::string& text);

}  // namespace hairrig
