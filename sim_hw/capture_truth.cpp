#include "sim_hw/capture_truth.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>

#include "core/parallel.h"
#include "core/sha256.h"
#include "core/strand_io.h"
#include "sim_hw/ground_truth.h"
#include "sim_hw/sim_devices.h"

namespace hairrig {
namespace {

constexpr double kAngleMatchDeg = 0.01;

// ground_truth.json: each view at the angle its frame was rendered at where
// known (`rendered_deg`), else at its stop's commanded angle.
Status WriteTruthJson(const Scene& scene, const std::vector<PlannedTruthView>& views,
                      const std::map<int, double>& rendered_deg, const std::string& dir,
                      const FileWriter& write) {
  std::vector<ViewGroundTruth> truths;
  for (const PlannedTruthView& v : views) {
    const int camera = scene.FindCamera(v.camera_serial);
    if (camera < 0) continue;
    const auto rendered = rendered_deg.find(v.view);
    const double angle = rendered != rendered_deg.end() ? rendered->second : v.turntable_deg;
    truths.push_back(MakeViewGroundTruth(scene, v.view, v.stop, camera, angle));
  }
  const std::string text = GroundTruthJson(scene, truths, /*with_maps=*/true);
  return write(dir + "/ground_truth.json", text.data(), text.size());
}

// The wig, turntable frame, as binary PLY.
Status WriteTruthStrands(const SimWorld& world, const std::string& dir, const FileWriter& write) {
  HR_ASSIGN_OR_RETURN(
      const std::vector<uint8_t> bytes,
      EncodeStrands(WorldRenderer(world).strands_turntable_mm(), StrandFormat::kPlyBinary));
  return write(dir + "/ground_truth_strands.ply", bytes.data(), bytes.size());
}

// The box the frames show, as built (the drawn box when the scene says nothing
// of its build), in the format a calibration's box_as_built.yaml has.
Status WriteTruthBox(const Scene& scene, const std::string& dir, const FileWriter& write) {
  const std::string text =
      CalibBoxYaml(scene.box,
                   "The calibration box of the simulated rig as built (ground truth).\n"
                   "Scene: " +
                       scene.path);
  return write(dir + "/box_as_built.yaml", text.data(), text.size());
}

std::vector<int> SceneCameras(const Scene& scene, const std::vector<PlannedTruthView>& views) {
  std::vector<int> cameras;
  for (const PlannedTruthView& v : views) cameras.push_back(scene.FindCamera(v.camera_serial));
  return cameras;
}

}  // namespace

struct CaptureGroundTruth::State {
  std::vector<PlannedTruthView> views;
  std::vector<int> scene_cameras;  // per view; -1: not a camera of the scene
  std::string dir, maps_dir;
  FileWriter file_writer;  // the capture's (empty: the file system)
  std::mutex mutex;
  std::map<int, double> written;  // view -> the turntable angle its maps were rendered at (deg)
  std::set<int> writing;          // views whose maps a camera's thread is writing now
  Status first_error;             // of any write: once set, nothing more is written
  bool recording = true;
  std::map<std::string, std::string> sha256;  // of each file written, by its path under dir

  // checksums.json: every file written so far with its SHA-256 (core/truth_maps.h).
  Status WriteChecksums() {
    std::map<std::string, std::string> sums;
    {
      std::lock_guard<std::mutex> lock(mutex);
      sums = sha256;
    }
    return WriteTruthChecksums(dir, sums, Writer());
  }

  // Writes with file_writer unless an earlier write failed; keeps the first failure.
  Status Write(const std::string& path, const void* data, size_t size) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!first_error.ok()) return first_error;
    }
    const Status s = WriteFileWith(file_writer, path, data, size);
    const std::string name = std::filesystem::path(path).lexically_relative(dir).generic_string();
    std::lock_guard<std::mutex> lock(mutex);
    if (!s.ok() && first_error.ok()) first_error = s;
    if (s.ok() && name != kTruthChecksumsFile) sha256[name] = Sha256Hex(data, size);
    return s;
  }
  FileWriter Writer() {
    return [this](const std::string& path, const void* data, size_t size) {
      return Write(path, data, size);
    };
  }

  void Record(int scene_camera, double turntable_deg, const ViewTruthMaps& maps) {
    for (size_t i = 0; i < views.size(); ++i) {
      const double off = std::remainder(turntable_deg - views[i].turntable_deg, 360.0);
      if (scene_cameras[i] != scene_camera || std::abs(off) > kAngleMatchDeg) continue;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (!recording || !first_error.ok() || written.count(views[i].view) > 0 ||
            writing.count(views[i].view) > 0)
          continue;
        writing.insert(views[i].view);
      }
      const Status s = WriteViewTruthMaps(maps_dir, views[i].view, maps, Writer());
      std::lock_guard<std::mutex> lock(mutex);
      writing.erase(views[i].view);
      if (s.ok())
        written[views[i].view] = turntable_deg;
      else if (first_error.ok())
        first_error = s;
    }
  }
};

CaptureGroundTruth::CaptureGroundTruth(SimWorld& world, std::shared_ptr<State> state)
    : world_(world), state_(std::move(state)) {}

Result<std::unique_ptr<CaptureGroundTruth>> CaptureGroundTruth::Begin(
    SimWorld& world, std::vector<PlannedTruthView> views, const std::string& capture_dir,
    FileWriter write) {
  const Scene& scene = WorldRenderer(world).scene();
  auto state = std::make_shared<State>();
  state->dir = capture_dir + "/ground_truth";
  state->maps_dir = state->dir + "/views";
  state->file_writer = std::move(write);
  std::error_code ec;
  std::filesystem::create_directories(state->maps_dir, ec);
  if (ec) return IoError(state->maps_dir + ": cannot create (" + ec.message() + ")");
  HR_RETURN_IF_ERROR(WriteTruthHeadMesh(scene, state->dir, state->Writer()));
  HR_RETURN_IF_ERROR(WriteTruthJson(scene, views, {}, state->dir, state->Writer()));
  HR_RETURN_IF_ERROR(WriteTruthStrands(world, state->dir, state->Writer()));
  HR_RETURN_IF_ERROR(WriteTruthBox(scene, state->dir, state->Writer()));
  HR_RETURN_IF_ERROR(state->WriteChecksums());
  state->scene_cameras = SceneCameras(scene, views);
  state->views = std::move(views);
  SetWorldTruthRecorder(world,
                        [state](int scene_camera, double turntable_deg, const ViewTruthMaps& maps) {
                          state->Record(scene_camera, turntable_deg, maps);
                        });
  return std::unique_ptr<CaptureGroundTruth>(new CaptureGroundTruth(world, std::move(state)));
}

CaptureGroundTruth::~CaptureGroundTruth() { StopRecording(); }

void CaptureGroundTruth::StopRecording() {
  bool was_recording;
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    was_recording = state_->recording;
    state_->recording = false;
  }
  if (was_recording) SetWorldTruthRecorder(world_, nullptr);
}

int CaptureGroundTruth::views_recorded() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return static_cast<int>(state_->written.size());
}

Status CaptureGroundTruth::Finish(const std::vector<int>& views_without_frames) {
  StopRecording();
  State& st = *state_;
  const std::set<int> skipped(views_without_frames.begin(), views_without_frames.end());
  std::vector<size_t> missing;
  {
    std::lock_guard<std::mutex> lock(st.mutex);
    HR_RETURN_IF_ERROR(st.first_error);
    for (size_t i = 0; i < st.views.size(); ++i) {
      const int view = st.views[i].view;
      if (st.scene_cameras[i] >= 0 && st.written.count(view) == 0 && skipped.count(view) == 0)
        missing.push_back(i);
    }
  }
  // Geometry only: unshaded, without noise, a view per thread.
  std::vector<Status> errors(missing.size());
  ParallelFor(missing.size(), 2, [&] {
    return [&](size_t k) {
      {
        std::lock_guard<std::mutex> lock(st.mutex);
        if (!st.first_error.ok()) return;  // nothing more is written: no render either
      }
      const PlannedTruthView& v = st.views[missing[k]];
      RenderOptions o;
      o.noise = false;
      o.threads = 1;
      o.ground_truth = true;
      o.shade_hair = false;
      auto view = WorldRenderer(world_).Render(st.scene_cameras[missing[k]], v.turntable_deg, o);
      errors[k] = view.ok() ? WriteViewTruthMaps(st.maps_dir, v.view, view->truth, st.Writer())
                            : view.status();
    };
  });
  {
    std::lock_guard<std::mutex> lock(st.mutex);
    HR_RETURN_IF_ERROR(st.first_error);  // the write that failed first, not one refused after it
  }
  for (const Status& s : errors) HR_RETURN_IF_ERROR(s);
  std::map<int, double> rendered_deg;
  {
    std::lock_guard<std::mutex> lock(st.mutex);
    rendered_deg = st.written;
  }
  if (!rendered_deg.empty()) {
    HR_RETURN_IF_ERROR(
        WriteTruthJson(WorldRenderer(world_).scene(), st.views, rendered_deg, st.dir, st.Writer()));
  }
  return st.WriteChecksums();
}

}  // namespace hairrig
