// Per-pixel ground truth of a simulated view (label, hair coverage, strand
// direction, depth, strand id) and its lossless files. The simulated rig
// (sim_hw/) writes them beside its renders and captures; evaluation reads them
// to score the reconstruction. Simulation-only data: production stages never
// take it as input.
#pragma once

#include <cstdint>
#include <map>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "core/camera_model.h"
#include "core/capture_storage.h"
#include "core/head_spec.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

// Per-pixel ground truth of one rendered view (pixel (0,0) is the centre of
// the top-left pixel; the same lens model as the image).
struct ViewTruthMaps {
  enum Label : uint8_t { kBackdrop = 0, kBox = 1, kHead = 2, kHair = 3 };
  cv::Mat label;            // CV_8U: Label. Hair where the hair's coverage is at least 0.5
  cv::Mat hair_alpha;       // CV_32F: hair coverage, 0..1 (all fibres, composited)
  cv::Mat orientation_deg;  // CV_32F: 2D direction of the front-most strand, [0, 180), image frame
                            // (0 = +x, 90 = +y, down the image); NaN where no strand
  cv::Mat depth_mm;         // CV_32F: depth of the front-most surface along the optical axis;
                            // for hair, the front-most strand's; 0 on the backdrop
  cv::Mat strand_id;        // CV_32S: index of the front-most strand in the wig; -1 where none
};

// Per-pixel ground truth of one view, lossless, in `dir` (created if missing):
//   NNN_label.png        8-bit: 0 backdrop, 1 box, 2 head, 3 hair
//   NNN_alpha.png        16-bit: hair coverage x 65535
//   NNN_orientation.png  16-bit: 2D strand direction in deg x 100 ([0, 18000)); 65535 where no
//   strand NNN_depth.png        16-bit: depth of the front-most surface in mm x kTruthDepthScale; 0
//   on the backdrop NNN_strand.png       16-bit: front-most strand index + 1; 0 where no strand
// NNN is the view number (three digits). A wig of 65,535 strands or more
// cannot be written (OutOfRange), nor a depth past 3,276 mm. Each file is
// written with `write` (core/capture_storage.h: a capture's storage and its
// free-space check; empty: the file system), in the order above; the first
// error ends the call.
constexpr int kTruthMapsVersion = 1;
constexpr double kTruthDepthScale = 20.0;  // 1/20 mm per count
Status WriteViewTruthMaps(const std::string& dir, int view, const ViewTruthMaps& maps,
                          const FileWriter& write = {});
// Reads what WriteViewTruthMaps wrote (the same units as ViewTruthMaps; the
// depth quantised to 0.05 mm, the angle to 0.01 deg). Errors name the file.
Result<ViewTruthMaps> ReadViewTruthMaps(const std::string& dir, int view);

// The true cameras of a simulated capture, as <capture>/ground_truth/
// ground_truth.json gives them (written by sim_hw/ground_truth.h).
struct CaptureTruth {
  struct View {
    std::string camera_serial;
    CameraIntrinsics intrinsics;
    Rigid3d cam_from_box;
  };
  Rigid3d turntable_from_box;
  std::map<int, View> views;  // by view number
  std::string views_dir;      // the per-view maps' folder (<capture>/ground_truth/views)
  std::string strands_file;   // the true strands, turntable frame
                              // (<capture>/ground_truth/ground_truth_strands.ply)
  // SHA-256 of each ground-truth file as written (checksums.json), by its path
  // relative to <capture>/ground_truth ("views/003_label.png").
  std::map<std::string, std::string> sha256;
  std::string dir;  // <capture>/ground_truth, resolved
  // The true head, turntable frame (ground_truth.json's "head", core/head_json.h);
  // its mesh_file is absolute or relative to the working folder, e.g.
  // <capture>/ground_truth/head_mesh.ply. Absent in captures written before the
  // ground truth recorded the head.
  std::optional<HeadSpec> head;
};

// The file of the ground truth's checksums, written last: every file of the
// ground truth, ground_truth.json included, with its SHA-256.
constexpr const char* kTruthChecksumsFile = "checksums.json";

// Writes <truth_dir>/checksums.json from `sha256` (path under truth_dir ->
// SHA-256) with `write` (core/capture_storage.h; empty: the file system).
Status WriteTruthChecksums(const std::string& truth_dir,
                           const std::map<std::string, std::string>& sha256,
                           const FileWriter& write = {});
// The SHA-256 of every regular file under `truth_dir` but checksums.json, for
// a ground truth whose writer kept no record of its own (a view set).
Result<std::map<std::string, std::string>> HashTruthFolder(const std::string& truth_dir);

// NotFound for a capture without ground truth (only the simulated rig writes
// one); CorruptData naming the file and field for a damaged one: a
// ground_truth/ folder or a file leading outside the capture, a file that does
// not match its checksum (ground_truth.json and the head's mesh are checked
// here), no checksums.json (a ground truth that was not finished: resume the
// capture), a head whose mesh file is missing.
Result<CaptureTruth> ReadCaptureTruth(const std::string& capture_dir);

// CorruptData naming `path` unless it lies inside truth.dir (symlinks
// resolved) and matches its checksum; NotFound when it is missing.
Status VerifyTruthFile(const CaptureTruth& truth, const std::string& path);

// ReadViewTruthMaps of truth.views_dir, each file verified first.
Result<ViewTruthMaps> ReadVerifiedViewTruthMaps(const CaptureTruth& truth, int view);

}  // namespace hairrig
