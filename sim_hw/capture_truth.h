// The ground truth of a simulated capture, written by the simulated rig
// beside the frames: <capture>/ground_truth/ground_truth.json (true cameras,
// box and turntable per planned view, the head), head_mesh.ply (the head's
// mesh, if it has one), ground_truth_strands.ply (the wig, turntable frame)
// and views/NNN_*.png (per-pixel maps, sim_hw/ground_truth.h), and last
// checksums.json, the SHA-256 of each of them (core/truth_maps.h), which the
// evaluation checks before it reads a file.
// The maps come from the very renders that make the frames: a view's maps
// are written when a simulated camera renders its frame, so the capture pays
// no second render. Every file is written with the capture's FileWriter
// (core/capture_storage.h: its storage and free-space check), so a full disk
// or the capture's storage.min_free_mb refuses a ground-truth file as it
// refuses a frame.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/capture_storage.h"
#include "core/status.h"

namespace hairrig {

class SimWorld;
struct ViewTruthMaps;

// One view of the capture plan, as the ground truth needs it.
struct PlannedTruthView {
  int view = 0;
  int stop = 0;
  std::string camera_serial;  // a camera of the scene
  double turntable_deg = 0;   // the stop's commanded angle
};

class CaptureGroundTruth {
 public:
  // Writes the JSON and the strands, then records the maps of each planned
  // view whose frame the world's cameras render (a render matches a view by
  // camera and by turntable angle, within 0.01 deg of the stop). Views of
  // cameras the scene lacks are left out. Every file goes through `write`
  // (empty: the file system); once a write fails, no further maps are
  // written while recording. Errors name the file.
  static Result<std::unique_ptr<CaptureGroundTruth>> Begin(SimWorld& world,
                                                           std::vector<PlannedTruthView> views,
                                                           const std::string& capture_dir,
                                                           FileWriter write = {});
  ~CaptureGroundTruth();  // stops recording

  // Stops recording, renders the maps of the views no camera rendered while
  // recording (a resumed capture's earlier views, views whose render did not
  // match) except `views_without_frames` (views a stopped or incomplete
  // capture has no frame of: their maps are written by the session that
  // shoots them), and rewrites ground_truth.json with each recorded view at
  // the angle its frame was rendered at (the simulated encoder's, within
  // 0.001 deg of the stop's); the first error of any write (a write that
  // failed while recording included: then nothing more is written).
  Status Finish(const std::vector<int>& views_without_frames = {});

  int views_recorded() const;  // maps written from the capture's own renders

 private:
  struct State;  // shared with the recorder, which may outlive this object on a camera's thread
  CaptureGroundTruth(SimWorld& world, std::shared_ptr<State> state);
  void StopRecording();

  SimWorld& world_;
  std::shared_ptr<State> state_;
};

}  // namespace hairrig
