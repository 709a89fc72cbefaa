#include "core/version.h"

#include <elf.h>
#include <link.h>

#include <cstring>
#include <mutex>

#include "core/sha256.h"

#ifndef HAIRRIG_VERSION
#error "HAIRRIG_VERSION is set by core/CMakeLists.txt from the project's VERSION"
#endif

namespace hairrig {

namespace {

// The hex GNU build ID in one loaded object's PT_NOTE segments; "" without one.
std::string BuildIdNote(const dl_phdr_info& object) {
  for (int i = 0; i < object.dlpi_phnum; ++i) {
    const ElfW(Phdr)& segment = object.dlpi_phdr[i];
    if (segment.p_type != PT_NOTE) continue;
    const char* at = reinterpret_cast<const char*>(object.dlpi_addr + segment.p_vaddr);
    const char* const end = at + segment.p_memsz;
    while (at + sizeof(ElfW(Nhdr)) <= end) {
      const auto* note = reinterpret_cast<const ElfW(Nhdr)*>(at);
      const char* name = at + sizeof(ElfW(Nhdr));
      const auto* desc =
          reinterpret_cast<const unsigned char*>(name + ((note->n_namesz + 3) & ~3u));
      at = reinterpret_cast<const char*>(desc) + ((note->n_descsz + 3) & ~3u);
      if (at > end) break;
      if (note->n_type != NT_GNU_BUILD_ID || note->n_namesz != 4 || std::memcmp(name, "GNU", 4))
        continue;
      static const char kHex[] = "0123456789abcdef";
      std::string hex;
      for (uint32_t k = 0; k < note->n_descsz; ++k) {
        hex += kHex[desc[k] >> 4];
        hex += kHex[desc[k] & 15];
      }
      return hex;
    }
  }
  return "";
}

// The main program's build ID (the first object dl_iterate_phdr lists).
std::string MainProgramBuildId() {
  std::string id;
  dl_iterate_phdr(
      [](dl_phdr_info* object, size_t, void* out) {
        *static_cast<std::string*>(out) = BuildIdNote(*object);
        return 1;  // the main program only
      },
      &id);
  return id;
}

}  // namespace

const char* HairrigVersion() { return HAIRRIG_VERSION; }

Result<std::string> HairrigBuildId() {
  static std::mutex mutex;
  static std::string build;  // kept once known; a failure is tried again next call
  std::lock_guard<std::mutex> lock(mutex);
  if (!build.empty()) return build;
  build = MainProgramBuildId();
  if (!build.empty()) return build;
  Result<std::string> hashed = Sha256OfFile("/proc/self/exe");
  if (!hashed.ok())
    return IoError(
        "hashing the running hairrig executable (/proc/self/exe, which has no build "
        "ID): " +
        hashed.status().message() + "; it must be readable by the user who runs it");
  build = "sha256:" + *hashed;
  return build;
}

}  // namespace hairrig
