// Strand file formats of the field, read and written without loss of geometry:
//
//   .hair  Cem Yuksel's format: 128-byte header ("HAIR", strand count, point
//          count, flags, defaults, 88-byte info), then optional uint16 segment
//          counts, float32 xyz points, optional thickness/transparency/colour.
//   .data  USC-HairSalon: int32 strand count, then per strand an int32 point
//          count and float32 xyz points.
//   .ply   a `vertex` element (x, y, z as float or double; optional uchar
//          red/green/blue) and a `strand` element with one integer property
//          (`nsegs`, segments per strand); an `edge` element is written for
//          tools that want it and ignored on reading. ascii and binary.
//
// Every reader checks each count against the bytes that are left before it
// allocates, so a truncated or corrupt file gives a CorruptData error naming
// the file and the field, never a crash or a huge allocation. Points are
// float32 in all three formats, so conversions are exact.
// Not kept: .hair per-point thickness and transparency (read and checked, then
// dropped); .hair colours are kept quantised to 8 bits.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/strands.h"

namespace hairrig {

enum class StrandFormat { kHair, kData, kPlyBinary, kPlyAscii };

const char* StrandFormatName(StrandFormat format);
// From the extension: .hair, .data, .ply (binary on writing).
Result<StrandFormat> StrandFormatFromPath(const std::string& path);

// `name` is used in messages only.
Result<StrandSet> DecodeStrands(const std::vector<uint8_t>& bytes, StrandFormat format,
                                const std::string& name);
Result<std::vector<uint8_t>> EncodeStrands(const StrandSet& strands, StrandFormat format);

// Format from the extension (PLY: whichever the header says).
Result<StrandSet> ReadStrands(const std::string& path);
// Format from the extension unless given; written atomically.
Status WriteStrands(const std::string& path, const StrandSet& strands);
Status WriteStrands(const std::string& path, const StrandSet& strands, StrandFormat format);

}  // namespace hairrig
