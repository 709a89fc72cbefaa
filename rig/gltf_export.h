// `hairrig export`: a capture's hair as binary glTF (core/gltf_writer.h),
// for Blender, three.js and other tools:
//
//   <out>.glb          every reconstructed strand (reconstruction/strands/
//                      strands.ply) as the node "strands", the subject's head
//                      as "head", and, with a simulation folder, its frames
//                      as an animated node named after the folder (characters
//                      other than letters, digits, '_' and '-' made '_'), each frame
//                      decimated as below (the frames' strand files are the
//                      simulation's data; 31 frames of 20,000 strands would
//                      be 1.8 GB), and the guides that drive them (the
//                      folder's guides/, every guide and point) as a second
//                      animated node, <name>_guides; both in
//                      animation_encoding (core/gltf_writer.h)
//   <out>.display.glb  the same scene with the strands decimated for display:
//                      at most display_strands strands (every k-th) of at most
//                      display_points points each (every j-th point, the tip
//                      kept); and, for the console's 3D view, the
//                      reconstruction's oriented points (reconstruction/
//                      points.ply, every k-th, at most display_cloud) as the
//                      node "points" coloured by direction (DirectionColour),
//                      and a simulated capture's true strands (ground_truth/
//                      ground_truth_strands.ply, decimated as the strands) as
//                      "truth" when the reconstruction is in the turntable
//                      frame; each only when its file exists and reads (else
//                      left out with a warning naming the file); the
//                      animation as frame nodes whatever animation_encoding
//                      (three.js r111, the console's, does not morph lines),
//                      without the guides
//
// Wisps: every strand set and the simulation's strands carry _WISP_ID, the
// guide each strand follows (cluster_of_strand of model_file, the output of
// `hairrig fit` on the reconstruction's strands), where that model has as
// many strands as the reconstruction (else none, with a warning).
//
// Units: the files are in metres, +y up; the capture's turntable frame
// (mm, +z up) is rotated into it. The head is, in order: head_file, the
// fitted reconstruction/head.yaml, the capture's rig.yaml head; none when the
// capture has neither (the summary says so).
//
// Errors: InvalidArgument for bad options; NotFound naming the strand file
// when the capture has no strands (run `hairrig reconstruct` first) or a
// simulation folder without frames; CorruptData when its guides/ holds
// another number of frames than frames/; the readers' errors naming the file; an
// IoError naming the output that cannot be written.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "core/gltf_writer.h"
#include "core/status.h"

namespace hairrig {

struct GltfExportOptions {
  std::string dir;              // a capture folder with reconstruction/strands/strands.ply
  std::string out_file;         // <out>.glb; empty: <dir>/reconstruction/strands/hair.glb
  std::string head_file;        // empty: the capture's (see above)
  std::string simulation_dir;   // a `hairrig simulate` output folder; empty: no animation
  std::string model_file;       // the fitted model naming each strand's wisp; empty:
                                // <dir>/simulation/model.json where it exists
  int display_strands = 2000;   // 1 .. 1,000,000
  int display_points = 32;      // 2 .. 10,000
  int display_cloud = 50000;    // 0 (no points) .. 10,000,000
  int animation_strands = 500;  // strands per animation frame, 1 .. 1,000,000
  // The full file's animations (the display copy's are frame nodes).
  GltfAnimationEncoding animation_encoding = GltfAnimationEncoding::kFrameNodes;
  int threads = 0;            // simulation frames read at once (each about 60 MB
                              // while read); 0: one per core
  bool display_only = false;  // write <out>.display.glb alone (the reconstruction does)

  // InvalidArgument naming the option.
  Status Check() const;
};

struct GltfExportSummary {
  GltfWriteSummary full, display;  // full.path empty when display_only
  std::string head_source;         // where the head came from; empty: no head
  int64_t truth_strands = 0;       // in the display level (counted in display.strands)
  int64_t cloud_points = 0;        // in the display level (counted in display.vertices)
  int64_t guides = 0;              // animated guides in the full level (counted in full.strands)
  int64_t wisps = 0;               // wisps the strands' _WISP_ID names; 0: none
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

struct OrientedPoint;

// What a caller holds in memory already (the reconstruction, which has just
// written them); null: read from the capture folder.
struct GltfExportInputs {
  const StrandSet* strands = nullptr;                  // as reconstruction/strands/strands.ply
  const std::vector<OrientedPoint>* points = nullptr;  // as reconstruction/points.ply
};

Result<GltfExportSummary> ExportCaptureGltf(const GltfExportOptions& options,
                                            const GltfExportInputs& inputs = {});

// At most `max_strands` strands (every k-th, k = ceil(strands / max_strands)),
// each with at most `max_points` points (every j-th, the tip kept); colours
// follow their points; `kept_strands`, when given, receives the kept strands'
// indices. max_strands >= 1 and max_points >= 2.
StrandSet DecimateStrands(const StrandSet& strands, int max_strands, int max_points,
                          std::vector<uint32_t>* kept_strands = nullptr);

// A unit direction (the points' object frame, unsigned) as a colour: red |x|, green
// |y|, blue |z| (vertical hair is blue), each 0..255.
std::array<uint8_t, 3> DirectionColour(const Eigen::Vector3f& direction);

}  // namespace hairrig
