// Procedural wigs for the simulated rig: roots spread over the head's scalp,
// strands that leave it along its normal (combed away from the parting) and
// fall under gravity, kept outside the head, in straight, wavy, curly
// (ringlets), bangs or file-guided styles. With wisps, strands clump around
// wisp centres with a clump profile, frizz and a few flyaways. Seeded: the same
// options give the same strands on every machine.
#pragma once

#include "core/head_model.h"
#include "core/status.h"
#include "core/strands.h"
#include "sim_hw/scene.h"

namespace hairrig {

// Strands in the turntable frame (mm), root first. For WigStyle::kFile the
// file's strands (placed by options.turntable_from_file) are the wisp guides.
// Errors name the field (wig.file; bad options as WigOptions::Check).
Result<StrandSet> GenerateWig(const WigOptions& options, const HeadModel& head);
// The same on the head the scene part describes (built for the call).
Result<StrandSet> GenerateWig(const WigOptions& options, const HeadSpec& head);

}  // namespace hairrig
