#include "rig/simulation_preview.h"

#include <mutex>

namespace hairrig {

namespace {
std::mutex& FactoryMutex() {
  static std::mutex mutex;
  return mutex;
}
StrandPreviewerFactory& Factory() {
  static StrandPreviewerFactory factory;
  return factory;
}
}  // namespace

void RegisterStrandPreviewer(StrandPreviewerFactory factory) {
  std::lock_guard<std::mutex> lock(FactoryMutex());
  Factory() = std::move(factory);
}

Result<std::unique_ptr<StrandPreviewer>> MakeStrandPreviewer(const std::string& scene_file,
                                                             const HeadSpec& head) {
  StrandPreviewerFactory factory;
  {
    std::lock_guard<std::mutex> lock(FactoryMutex());
    factory = Factory();
  }
  if (!factory) {
    return FailedPrecondition(
        "this program has no strand renderer for previews: ask for none (--preview-every 0)");
  }
  return factory(scene_file, head);
}

}  // namespace hairrig
