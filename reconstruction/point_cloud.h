// The reconstruction's oriented point cloud and its PLY file (points.ply).
//
// Each point is a position on a strand and the strand's direction there.
// Positions are mm in the object frame of the input (ReconstructionInput::
// object_frame: the turntable frame for a capture of this rig).
//
// File layout, one `vertex` element so that MeshLab and CloudCompare show the
// directions as normals:
//   property float x, y, z            position (mm)
//   property float nx, ny, nz         unit strand direction (unsigned)
//   property float confidence         0..1
//   property list uchar ushort views  indices into ReconstructionInput::views
// The writer writes binary little endian; the reader takes any PLY encoding.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

struct OrientedPoint {
  Eigen::Vector3f position_mm =
      Eigen::Vector3f::Zero();  // object frame (turntable frame for a capture)
  Eigen::Vector3f direction =
      Eigen::Vector3f::Zero();  // unit strand direction, unsigned (d and -d are the same)
  float confidence = 0;         // 0..1
  std::vector<uint16_t> views;  // indices into ReconstructionInput::views that see the point
};

// Writes `points` to `path` atomically (core/file_util.h: a reader never sees
// half a file). The list's count is `uchar`, or `ushort` when a point lists
// more than 255 views. InvalidArgument (naming the point) for a non-finite
// position, direction or confidence, or more than 65535 views; IoError when
// the file cannot be written.
Status WritePointCloudPly(const std::string& path, const std::vector<OrientedPoint>& points);

// Reads a point cloud written by WritePointCloudPly or another tool (ascii or
// binary of either byte order, any numeric property types, properties in any
// order, other elements and properties ignored). x y z nx ny nz are required;
// without `confidence` a point gets 1 (the tool that wrote it vouches for
// it), without `views` an empty list. Directions are returned as stored (not
// renormalised). NotFound/IoError when the file cannot be read; CorruptData
// naming the file for a malformed header, a missing property, a count larger
// than the file's bytes can hold, a truncated body, a non-finite value or a
// view index that is not an integer in 0..65535 (naming the vertex).
Result<std::vector<OrientedPoint>> ReadPointCloudPly(const std::string& path);

}  // namespace hairrig
