// Hair as a binary glTF 2.0 file (.glb), the format Blender, three.js and
// most DCC tools import without a plug-in (Khronos glTF 2.0 specification):
//
//   - every strand set is one node holding one LINES primitive (an index
//     pair per segment, so the strands of a set share one draw call; a
//     strand is a connected run of segments): POSITION, COLOR_0 where the
//     strands carry colours (RGBA8, normalised), _STRAND_ID (FLOAT, the
//     strand's index in its set) for tools that split the strands again, and
//     _WISP_ID (FLOAT) where the set names each strand's wisp (the guide it
//     follows);
//   - every triangle mesh (the head) is one node with POSITION, NORMAL and
//     TRIANGLES;
//   - every point cloud is one node holding one POINTS primitive: POSITION
//     and COLOR_0 where the points carry colours;
//   - an animation (simulated strands, one StrandSet per frame, all of the
//     same topology) is a node named like the animation, in one of two
//     encodings (GltfAnimationEncoding):
//       frame nodes: the node's children are the frames, each a LINES node
//       sharing one index buffer; the animation shows each frame at its time
//       (k / fps) by a STEP animation of the frames' scale (1 on its frame,
//       0 elsewhere), with a last key at n / fps so that the animation lasts
//       n / fps; without the animation the first frame shows;
//       morph targets: the node holds frame 0 as one LINES primitive whose
//       morph target k - 1 is frame k's offset from frame 0; the animation
//       sets target k - 1's weight to 1 at k / fps (LINEAR: a player blends
//       between frames), a last key at n / fps; a player without morph
//       targets on lines (three.js r111) shows frame 0.
//
// Units and frames: the input is in mm in the turntable (or object) frame,
// +z up; the file is in metres with +y up as glTF requires:
// (x, y, z) mm -> (x, z, -y) / 1000 m, a rotation, so handedness is kept.
//
// Failure modes: InvalidArgument for a set with no strands or more than
// 2^24 (the strand id is a float), wisps of another count than its strands
// or at 2^24 or more, a StrandSet whose counts do not sum to
// its points, colours of another count than its points, a non-finite
// coordinate (naming the set and the point), a triangle that indexes past
// its mesh's vertices, an empty point cloud or one whose colours are of
// another count than its points, frames of differing topology or fps not positive;
// IoError naming the path when the file cannot be written (written
// atomically: a failed write leaves no partial file).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/strands.h"
#include "core/triangle_mesh.h"

namespace hairrig {

struct GltfStrandSet {
  std::string name;                                        // the node's and the mesh's name
  const StrandSet* strands = nullptr;                      // mm, +z up
  std::array<float, 4> colour{0.35f, 0.22f, 0.12f, 1.0f};  // linear RGBA, the material's
  const std::vector<uint32_t>* wisps = nullptr;            // per strand (< 2^24), or null
};

struct GltfTriangleMesh {
  std::string name;
  const TriangleMesh* mesh = nullptr;  // mm, +z up
  std::array<float, 4> colour{0.8f, 0.7f, 0.62f, 1.0f};
};

struct GltfPointCloud {
  std::string name;
  const std::vector<Eigen::Vector3f>* points_mm = nullptr;       // mm, +z up
  const std::vector<std::array<uint8_t, 3>>* colours = nullptr;  // per point (COLOR_0), or null
  std::array<float, 4> colour{0.9f, 0.9f, 0.9f, 1.0f};           // linear RGBA, the material's
};

enum class GltfAnimationEncoding { kFrameNodes, kMorphTargets };

struct GltfStrandAnimation {
  std::string name;                      // the node's and the animation's name
  std::vector<const StrandSet*> frames;  // mm, +z up, every frame the same point counts
  double fps = 30;
  std::array<float, 4> colour{0.35f, 0.22f, 0.12f, 1.0f};
  GltfAnimationEncoding encoding = GltfAnimationEncoding::kFrameNodes;
  const std::vector<uint32_t>* wisps = nullptr;  // per strand of a frame, or null
};

struct GltfScene {
  std::string generator = "hairrig";  // asset.generator
  std::vector<GltfStrandSet> strand_sets;
  std::vector<GltfTriangleMesh> meshes;
  std::vector<GltfPointCloud> point_clouds;
  std::vector<GltfStrandAnimation> animations;
};

struct GltfWriteSummary {
  std::string path;
  int64_t bytes = 0;
  int nodes = 0;
  int64_t strands = 0;   // over the strand sets (an animation's strands counted once)
  int64_t vertices = 0;  // strand, mesh and point vertices, every frame of frame-node
                         // animations, frame 0 of morph-target ones (glTF's count)
  int64_t segments = 0;  // over the strand sets and one frame of each animation
  int frames = 0;        // over the animations
};

// Writes `scene` to `path` (.glb). See the file comment for the layout and errors.
Result<GltfWriteSummary> WriteGlb(const std::string& path, const GltfScene& scene);

// The same file's bytes, for tests and servers that send it.
Result<std::vector<uint8_t>> EncodeGlb(const GltfScene& scene, GltfWriteSummary* summary = nullptr);

}  // namespace hairrig
