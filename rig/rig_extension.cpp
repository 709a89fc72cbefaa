#include "rig/rig_extension.h"

#include <algorithm>
#include <mutex>

namespace hairrig {

namespace {

struct ExtensionList {
  std::mutex mutex;
  std::vector<std::shared_ptr<const RigExtension>> extensions;
};

ExtensionList& Extensions() {
  static ExtensionList list;
  return list;
}

}  // namespace

void RegisterRigExtension(std::shared_ptr<const RigExtension> extension) {
  if (!extension) return;
  ExtensionList& list = Extensions();
  std::lock_guard<std::mutex> lock(list.mutex);
  if (std::find(list.extensions.begin(), list.extensions.end(), extension) != list.extensions.end())
    return;
  list.extensions.push_back(std::move(extension));
}

std::vector<std::shared_ptr<const RigExtension>> RegisteredRigExtensions() {
  ExtensionList& list = Extensions();
  std::lock_guard<std::mutex> lock(list.mutex);
  return list.extensions;
}

}  // namespace hairrig
