#include "rig/capture.h"

#include <algorithm>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "core/contact_sheet.h"
#include "core/file_util.h"
#include "core/image_file.h"
#include "core/log.h"
#include "rig/capture_calibration_input.h"
#include "rig/capture_dataset.h"
#include "rig/capture_plan.h"
#include "rig/capture_sequencer.h"
#include "rig/rig_config.h"

namespace hairrig {

namespace fs = std::filesystem;

nlohmann::json CaptureSummary::ToJson() const {
  return {{"dir", dir},
          {"status", status},
          {"message", message},
          {"views_planned", views_planned},
          {"views_completed", views_completed},
          {"views_kept", views_kept},
          {"frames", frames},
          {"bytes", bytes},
          {"faults", faults},
          {"missing_views", missing_views},
          {"setup_s", setup_s},
          {"wall_s", wall_s},
          {"lower_bound_s", lower_bound_s},
          {"efficiency", efficiency}};
}

namespace {

// <capture>/contact_sheet.png from the verified frames, in plan order, unless
// it would leave less than storage.min_free_mb free (IoError, as a failed write).
Status WriteContactSheet(CaptureDataset& dataset, const CapturePlan& plan) {
  std::vector<cv::Mat> thumbs;
  std::vector<std::string> labels;
  for (const FrameRecord& r : dataset.VerifiedFrames()) {
    Result<cv::Mat> image = ReadImageFile(dataset.dir() + "/" + r.file, cv::IMREAD_REDUCED_COLOR_4);
    if (!image.ok()) continue;
    thumbs.push_back(std::move(image).value());
    labels.push_back(std::filesystem::path(r.file).filename().string());
  }
  if (thumbs.empty()) return Status::Ok();
  const int columns = std::max<int>(
      1, static_cast<int>(plan.views.size() / std::max<size_t>(1, plan.stops.size())) * 4);
  const cv::Mat sheet = MakeContactSheet(thumbs, labels, columns, 240);
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", sheet, png)) return Internal("contact sheet: PNG encoding failed");
  return dataset.WriteFile(dataset.dir() + "/contact_sheet.png", png.data(), png.size());
}

std::string ReadText(const std::string& path) {
  auto bytes = ReadFileBytes(path);
  return bytes.ok() ? std::string(bytes->begin(), bytes->end()) : std::string();
}

// The plan as the journal's view_planned records.
std::vector<PlannedViewRecord> PlannedViewRecords(const CapturePlan& plan) {
  std::vector<PlannedViewRecord> records;
  for (const PlannedView& v : plan.views) {
    const PlannedStop& stop = plan.stops[static_cast<size_t>(v.stop)];
    records.push_back(
        {v.index, v.stop, stop.angle_deg, v.camera_name, v.camera_serial, stop.light_levels});
  }
  return records;
}

// The config of this session: the rig config, or a resumed capture's
// snapshot (*config_text is left empty then). A rig built without its
// extensions (a replay) ignores the config sections they would read.
Result<RigConfig> LoadSessionConfig(const CaptureOptions& options, std::string* config_text) {
  const UnclaimedSections unclaimed =
      options.rig_build.attach_extensions ? UnclaimedSections::kRefuse : UnclaimedSections::kIgnore;
  if (options.resume) {
    HR_ASSIGN_OR_RETURN(const CaptureMetadata metadata, ReadResumableCapture(options.out_dir));
    const fs::path snapshot = fs::absolute(options.out_dir).lexically_normal() / "rig.yaml";
    return LoadRigConfig(snapshot.string(), metadata.config_dir, unclaimed);
  }
  if (fs::exists(options.out_dir)) {
    return FailedPrecondition(
        options.out_dir +
        " already exists: choose a new --out folder, or add --resume to continue it");
  }
  if (options.rig) {  // the rig's own config, as it was loaded
    *config_text = ReadText(options.rig->config.path);
    return options.rig->config;
  }
  HR_ASSIGN_OR_RETURN(RigConfig config,
                      LoadRigConfig(options.config_path, options.config_relative_to, unclaimed));
  *config_text = ReadText(options.config_path);
  return config;
}

// Room on the capture's disk for the views left to shoot: all of them, or
// those of a resumed capture (`resumed`) without a verified frame.
Status CheckSpaceToFinish(const CaptureStorage& storage, const std::string& out_dir,
                          const CapturePlan& plan, const DeviceSet& devices,
                          const CapturePolicies& policies, const CaptureDataset* resumed) {
  std::vector<int> left;
  for (const PlannedView& v : plan.views) {
    if (!resumed || !resumed->HasVerifiedFrame(v.index)) left.push_back(v.index);
  }
  // The file system the capture lands on: the nearest folder that exists.
  fs::path probe = fs::absolute(out_dir);
  while (!fs::exists(probe) && probe.has_parent_path() && probe != probe.parent_path())
    probe = probe.parent_path();
  HR_ASSIGN_OR_RETURN(const uint64_t free, storage.FreeBytes(probe.string()));
  const uint64_t needed = BytesNeededToFinish(plan, devices, left, policies);
  if (free >= needed) return Status::Ok();
  return IoError(
      probe.string() + ": " + std::to_string(free / 1000000) + " MB free, the " +
      std::to_string(left.size()) + " views left to shoot need up to " +
      std::to_string(needed / 1000000) + " MB (their frames plus storage.min_free_mb): " +
      (resumed ? "free space, then run --resume again" : "free space or choose another --out"));
}

// Journals the session's start (and a new capture's plan) and writes the
// manifest; the first error.
Status StartSession(CaptureDataset& dataset, const CaptureOptions& options,
                    const std::string& subject, const RigConfig& config, const CapturePlan& plan,
                    const std::vector<PlannedViewRecord>& planned_views,
                    const ResumeReport& report) {
  HR_RETURN_IF_ERROR(dataset.Append({{"event", "session_start"},
                                     {"resume", options.resume},
                                     {"subject", subject},
                                     {"rig", config.name},
                                     {"config_dir", config.relative_to},
                                     {"views_planned", plan.views.size()},
                                     {"frames_verified", report.frames_verified},
                                     {"quarantined", report.quarantined},
                                     {"partial_removed", report.partial_removed.size()}}));
  if (!options.resume) HR_RETURN_IF_ERROR(dataset.JournalPlan(planned_views));
  return dataset.WriteManifest("in_progress");
}

// A storage failure (IoError) stops the session (Sequencer::StopForStorage)
// and is Ok here; any other error is returned.
Status StopIfStorage(Sequencer& sequencer, const Status& status) {
  if (status.code() != StatusCode::kIoError) return status;
  sequencer.StopForStorage(status);
  return Status::Ok();
}

}  // namespace

std::shared_ptr<CaptureStorage> CaptureStorageFor(const CaptureOptions& options, const Rig* rig) {
  if (options.storage) return options.storage;
  if (rig && rig->capture_storage) return rig->capture_storage;
  return DefaultCaptureStorage();
}

Status CaptureOptions::Check() const {
  if (out_dir.empty())
    return InvalidArgument("--out is required: the folder the capture is written to");
  return rig_build.Check().WithContext("rig_build");
}

Result<CaptureSummary> RunCapture(const CaptureOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  std::string config_text;
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadSessionConfig(options, &config_text));
  std::unique_ptr<Rig> built;
  if (!options.rig) {
    HR_ASSIGN_OR_RETURN(built, BuildRig(config, options.rig_build));
  }
  Rig* const rig = options.rig ? options.rig : built.get();
  HR_ASSIGN_OR_RETURN(CapturePlan plan, ReadCapturePlan(config.root, rig->devices));
  HR_ASSIGN_OR_RETURN(CapturePolicies policies, ReadCapturePolicies(config.root));
  HR_RETURN_IF_ERROR(CheckCalibrationSection(config));
  const std::shared_ptr<CaptureStorage> storage = CaptureStorageFor(options, rig);
  DatasetOptions dataset_options;
  dataset_options.png_compression = policies.png_compression;
  dataset_options.min_free_bytes = policies.MinFreeBytes();
  const std::vector<PlannedViewRecord> planned_views = PlannedViewRecords(plan);
  std::unique_ptr<CaptureDataset> dataset;
  ResumeReport report;
  if (options.resume) {
    HR_ASSIGN_OR_RETURN(
        dataset, CaptureDataset::OpenForResume(options.out_dir, dataset_options, &report, storage));
    // A resumed capture's plan is checked before anything else is written.
    HR_RETURN_IF_ERROR(dataset->JournalPlan(planned_views));
  }
  HR_RETURN_IF_ERROR(
      CheckSpaceToFinish(*storage, options.out_dir, plan, rig->devices, policies, dataset.get()));
  if (!options.resume) {
    CaptureMetadata metadata;
    metadata.config_source = fs::absolute(config.path).lexically_normal().string();
    metadata.config_dir = config.relative_to;
    metadata.subject = options.subject;
    HR_ASSIGN_OR_RETURN(dataset, CaptureDataset::Create(options.out_dir, config_text, metadata,
                                                        dataset_options, storage));
  }
  const std::string subject = options.resume ? dataset->metadata().subject : options.subject;
  dataset->SetPlanSummary(static_cast<int>(plan.views.size()), subject, config.name);
  Sequencer sequencer(*rig, plan, policies, *dataset, options);
  // From here on a storage failure stops the session, resumable, and the call returns a summary.
  HR_RETURN_IF_ERROR(StopIfStorage(
      sequencer, StartSession(*dataset, options, subject, config, plan, planned_views, report)));
  const CaptureFolder folder{dataset->dir(), sequencer.ObserverWriter()};
  Status begun = Status::Ok();
  for (const auto& observer : rig->capture_observers) {
    if (!begun.ok() || sequencer.Stopping()) break;
    begun = StopIfStorage(sequencer, observer->OnCaptureBegin(plan, folder));
  }
  if (begun.ok()) sequencer.Run();
  rig->devices.CloseAll();
  const CaptureSummary shot = sequencer.Summary();
  // Every observer is told, so that none writes through `folder` after this
  // call. A storage failure stops the session; the first other error is returned.
  Status ended = Status::Ok();
  for (const auto& observer : rig->capture_observers) {
    const Status s = StopIfStorage(sequencer, observer->OnCaptureEnd(shot));
    if (ended.ok()) ended = s;
  }
  HR_RETURN_IF_ERROR(begun);
  if (ended.ok() && !sequencer.StorageFailed()) {
    const Status sheet = WriteContactSheet(*dataset, plan);
    if (!StopIfStorage(sequencer, sheet).ok()) LogWarning(sheet.ToString());
  }
  CaptureSummary summary = sequencer.Summary();
  sequencer.EndSession(&summary);
  HR_RETURN_IF_ERROR(ended);
  return summary;
}

}  // namespace hairrig
