// Procedural wigs for the simulated rig: roots spread over the scalp of the
// ellipsoid head, strands that leave the scalp along its normal and fall under
// gravity, kept outside the head, in straight, wavy or curly styles. Seeded:
// the same options give the same strands on every machine.
#pragma once

#include "core/status.h"
#include "core/strands.h"
#include "sim_hw/scene.h"

namespace hairrig {

// Strands in the turntable frame (mm), root first. For WigStyle::kFile the
// strands are read from options.file (turntable frame, mm).
Result<StrandSet> GenerateWig(const WigOptions& options, const SceneHead& head);

}  // namespace hairrig
