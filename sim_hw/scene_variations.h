// Named departures of a scene towards what photographs of a real rig show:
// another ISO, JPEG, defocus, white balance and exposure errors, a panel
// dimmed or off, harder or softer light, other mannequins and backdrops,
// fibre-level sparkle. A scene file lists them under `variations:` (applied
// after the file's own values, in order); the robustness bench
// (bench/robustness_bench.cpp) runs the pipeline under each.
#pragma once

#include <string>
#include <vector>

#include "core/status.h"
#include "sim_hw/scene.h"

namespace hairrig {

struct SceneVariation {
  std::string name;         // e.g. "iso1600"
  std::string description;  // what it changes, in a few words
  void (*apply)(Scene* scene) = nullptr;
};

// Every variation, in the order the robustness table lists them. The last,
// "photograph", combines several (a DSLR's JPEG at ISO 800, defocus, a warm
// white balance, fibre sparkle, a grey backdrop and a white mannequin).
const std::vector<SceneVariation>& SceneVariations();

// Applies the named variations in order. InvalidArgument naming the unknown
// name and listing the known ones.
Status ApplySceneVariations(const std::vector<std::string>& names, Scene* scene);

}  // namespace hairrig
