#include "rig/capture_dataset.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/file_util.h"
#include "core/sha256.h"
#include "rig/crash_points.h"
#include "rig/safe_names.h"

namespace hairrig {

namespace fs = std::filesystem;

std::string UtcNow() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return text;
}

namespace {

constexpr const char* kJournal = "journal.jsonl";
constexpr const char* kManifest = "manifest.json";
constexpr const char* kMetadata = "capture.json";

Status WriteAll(int fd, const char* p, size_t size, const std::string& what) {
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return IoError(what + ": write failed (" + std::strerror(errno) + ")");
    }
    p += n;
    size -= static_cast<size_t>(n);
  }
  return Status::Ok();
}

// Moves `file` into <dir>/quarantine/ under a name not yet taken.
Result<std::string> Quarantine(const std::string& dir, const fs::path& file) {
  const fs::path q = fs::path(dir) / "quarantine";
  std::error_code ec;
  fs::create_directories(q, ec);
  fs::path target = q / file.filename();
  for (int n = 1; fs::exists(target); ++n)
    target = q / (file.filename().string() + "." + std::to_string(n));
  fs::rename(file, target, ec);
  if (ec) return IoError(file.string() + ": cannot move it to quarantine/ (" + ec.message() + ")");
  return target.string();
}

}  // namespace

Result<std::vector<nlohmann::json>> ReadJournalRecords(const std::string& journal_path,
                                                       size_t* cut_short_bytes) {
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, ReadFileBytes(journal_path));
  std::vector<nlohmann::json> records;
  size_t line_start = 0;
  for (size_t i = 0; i < bytes.size(); ++i) {
    if (bytes[i] != '\n') continue;
    nlohmann::json record =
        nlohmann::json::parse(bytes.begin() + static_cast<long>(line_start),
                              bytes.begin() + static_cast<long>(i), nullptr, false);
    if (record.is_discarded() || !record.is_object()) {
      return CorruptData(
          journal_path + ": line " + std::to_string(records.size() + 1) +
          " is not a JSON record and is not the last one; the journal was altered. Keep a copy, "
          "then remove that line by hand");
    }
    records.push_back(std::move(record));
    line_start = i + 1;
  }
  if (cut_short_bytes) *cut_short_bytes = bytes.size() - line_start;
  return records;
}

CaptureDataset::CaptureDataset(std::string dir, DatasetOptions options)
    : dir_(std::move(dir)), options_(options) {}

CaptureDataset::~CaptureDataset() {
  if (journal_fd_ >= 0) ::close(journal_fd_);
}

Status CaptureDataset::OpenJournal() {
  const std::string path = dir_ + "/" + kJournal;
  journal_fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (journal_fd_ < 0)
    return IoError(path + ": cannot open for appending (" + std::strerror(errno) + ")");
  // One writer per capture: a second hairrig on the same folder is refused.
  if (::flock(journal_fd_, LOCK_EX | LOCK_NB) != 0) {
    return FailedPrecondition(
        dir_ + " is being written by another hairrig process; wait for it to finish");
  }
  return Status::Ok();
}

Result<std::unique_ptr<CaptureDataset>> CaptureDataset::Create(const std::string& dir,
                                                               const std::string& config_text,
                                                               nlohmann::json metadata,
                                                               const DatasetOptions& options) {
  std::error_code ec;
  if (fs::exists(dir, ec)) {
    return FailedPrecondition(
        dir + " already exists: choose a new --out folder, or add --resume to continue it");
  }
  const fs::path parent = fs::absolute(dir).parent_path();
  fs::create_directories(parent, ec);
  if (!fs::is_directory(parent, ec))
    return IoError(parent.string() + ": cannot create the folder to hold the capture");
  if (!fs::create_directory(dir, ec) || !fs::create_directory(fs::path(dir) / "frames", ec)) {
    return IoError(dir + ": cannot create the capture folder (" + ec.message() + ")");
  }
  auto dataset = std::unique_ptr<CaptureDataset>(
      new CaptureDataset(fs::absolute(dir).lexically_normal().string(), options));
  HR_RETURN_IF_ERROR(WriteFileAtomic(dataset->ConfigSnapshotPath(), config_text));
  metadata["format"] = "hairrig-capture";
  metadata["version"] = 1;
  metadata["created_utc"] = UtcNow();
  HR_RETURN_IF_ERROR(WriteFileAtomic(dataset->dir_ + "/" + kMetadata, metadata.dump(2) + "\n"));
  dataset->metadata_ = std::move(metadata);
  HR_RETURN_IF_ERROR(dataset->OpenJournal());
  HR_RETURN_IF_ERROR(SyncFolder(parent.string()));
  return dataset;
}

Result<std::unique_ptr<CaptureDataset>> CaptureDataset::OpenForResume(const std::string& dir,
                                                                      const DatasetOptions& options,
                                                                      ResumeReport* report) {
  std::error_code ec;
  if (!fs::is_regular_file(fs::path(dir) / kJournal, ec)) {
    return NotFound(dir + " is not a capture folder (no " + kJournal + "): nothing to resume");
  }
  auto dataset = std::unique_ptr<CaptureDataset>(
      new CaptureDataset(fs::absolute(dir).lexically_normal().string(), options));
  const std::string metadata_path = dataset->dir_ + "/" + kMetadata;
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> metadata, ReadFileBytes(metadata_path));
  dataset->metadata_ = nlohmann::json::parse(metadata.begin(), metadata.end(), nullptr, false);
  if (!dataset->metadata_.is_object() ||
      dataset->metadata_.value("format", "") != "hairrig-capture") {
    return CorruptData(metadata_path +
                       " is not a hairrig capture description: was the folder made by hairrig?");
  }
  ResumeReport local;
  HR_RETURN_IF_ERROR(dataset->Repair(report ? report : &local));
  return dataset;
}

// Reads the journal, cuts a record left half-written, verifies frames and
// clears out what no record vouches for.
Status CaptureDataset::Repair(ResumeReport* report) {
  const std::string journal_path = dir_ + "/" + kJournal;
  HR_ASSIGN_OR_RETURN(records_, ReadJournalRecords(journal_path, &report->journal_bytes_dropped));
  if (report->journal_bytes_dropped > 0 &&
      ::truncate(journal_path.c_str(), static_cast<off_t>(fs::file_size(journal_path) -
                                                          report->journal_bytes_dropped)) != 0) {
    return IoError(journal_path + ": cannot cut the interrupted record (" + std::strerror(errno) +
                   ")");
  }
  HR_RETURN_IF_ERROR(OpenJournal());
  for (const auto& r : records_) {
    next_seq_ = std::max<int64_t>(next_seq_, r.value("seq", int64_t{0}) + 1);
    if (r.value("event", "") == "frame_stored") ++frames_written_;
  }
  if (report->journal_bytes_dropped > 0) {
    HR_RETURN_IF_ERROR(AppendLocked({{"event", "journal_repaired"},
                                     {"bytes_dropped", report->journal_bytes_dropped},
                                     {"why", "a record was cut short by the interruption"}}));
  }
  // Frames vouched for by the journal: the last record per view.
  std::map<int, nlohmann::json> claimed;
  for (const auto& r : records_) {
    if (r.value("event", "") == "frame_stored") claimed[r.at("view").get<int>()] = r;
  }
  std::map<std::string, int> file_to_view;
  for (const auto& [view, r] : claimed) {
    const std::string path = dir_ + "/" + r.at("file").get<std::string>();
    if (!PathIsInside(path, dir_))
      return CorruptData(dir_ + "/" + kJournal + ": frame file outside the capture folder");
    auto sha = Sha256OfFile(path);
    if (sha.ok() && *sha == r.at("sha256").get<std::string>()) {
      verified_[view] = r;
      file_to_view[fs::path(path).filename().string()] = view;
    }
  }
  report->frames_verified = static_cast<int>(verified_.size());
  for (const auto& entry : fs::directory_iterator(fs::path(dir_) / "frames")) {
    const std::string name = entry.path().filename().string();
    if (file_to_view.count(name)) continue;
    if (name.find(".tmp.") != std::string::npos) {
      fs::remove(entry.path());
      report->partial_removed.push_back(name);
      HR_RETURN_IF_ERROR(AppendLocked({{"event", "partial_removed"}, {"file", "frames/" + name}}));
      continue;
    }
    HR_ASSIGN_OR_RETURN(std::string moved, Quarantine(dir_, entry.path()));
    const std::string why = "no journal record vouches for it (or its checksum does not match)";
    report->quarantined.push_back(name + ": " + why);
    HR_RETURN_IF_ERROR(
        AppendLocked({{"event", "file_quarantined"},
                      {"file", "frames/" + name},
                      {"moved_to", fs::path(moved).lexically_relative(dir_).string()},
                      {"why", why}}));
  }
  for (const auto& entry : fs::directory_iterator(dir_)) {
    if (entry.path().filename().string().find(".tmp.") != std::string::npos)
      fs::remove(entry.path());
  }
  return Status::Ok();
}

std::vector<nlohmann::json> CaptureDataset::Records() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return records_;
}

Status CaptureDataset::Append(nlohmann::json record) {
  std::lock_guard<std::mutex> lock(mutex_);
  return AppendLocked(std::move(record));
}

Status CaptureDataset::AppendLocked(nlohmann::json record) {
  record["seq"] = next_seq_;
  record["time_utc"] = UtcNow();
  const std::string line = record.dump() + "\n";
  const std::string what = dir_ + "/" + kJournal;
  const size_t half = line.size() / 2;
  HR_RETURN_IF_ERROR(WriteAll(journal_fd_, line.data(), half, what));
  CrashPoint("journal_half_written");
  HR_RETURN_IF_ERROR(WriteAll(journal_fd_, line.data() + half, line.size() - half, what));
  if (::fdatasync(journal_fd_) != 0)
    return IoError(what + ": fsync failed (" + std::strerror(errno) + ")");
  ++next_seq_;
  records_.push_back(std::move(record));
  return Status::Ok();
}

Result<std::vector<uint8_t>> CaptureDataset::EncodeForStorage(const Frame& frame,
                                                              const FrameContext& context,
                                                              cv::Mat* image,
                                                              std::string* extension) const {
  const std::string who =
      "view " + std::to_string(context.view) + " from camera " + frame.camera_serial;
  const bool size_known = context.expected_width_px > 0 && context.expected_height_px > 0;
  if (frame.format == PixelFormat::kEncoded) {
    const std::string ext = FileNamePart(frame.encoding);
    *image = cv::imdecode(frame.data, cv::IMREAD_UNCHANGED);
    if (image->empty())
      return CorruptData(who + ": the " + ext + " file does not decode (" +
                         std::to_string(frame.data.size()) + " bytes)");
    if (size_known &&
        (image->cols != context.expected_width_px || image->rows != context.expected_height_px)) {
      return CorruptData(who + ": decodes to " + std::to_string(image->cols) + "x" +
                         std::to_string(image->rows) + ", expected " +
                         std::to_string(context.expected_width_px) + "x" +
                         std::to_string(context.expected_height_px));
    }
    *extension = ext;
    return frame.data;
  }
  if (frame.width_px <= 0 || frame.height_px <= 0 || frame.data.size() != frame.ExpectedBytes()) {
    return CorruptData(who + ": " + std::to_string(frame.data.size()) + " bytes for a " +
                       std::to_string(frame.width_px) + "x" + std::to_string(frame.height_px) +
                       " " + PixelFormatName(frame.format) + " frame (expected " +
                       std::to_string(frame.ExpectedBytes()) + ")");
  }
  if (size_known && (frame.width_px != context.expected_width_px ||
                     frame.height_px != context.expected_height_px)) {
    return CorruptData(who + ": frame is " + std::to_string(frame.width_px) + "x" +
                       std::to_string(frame.height_px) + ", the camera's sensor is " +
                       std::to_string(context.expected_width_px) + "x" +
                       std::to_string(context.expected_height_px));
  }
  const int channels = BytesPerPixel(frame.format);
  const cv::Mat raw(frame.height_px, frame.width_px, channels == 3 ? CV_8UC3 : CV_8UC1,
                    const_cast<uint8_t*>(frame.data.data()));
  if (frame.format == PixelFormat::kRgb8)
    cv::cvtColor(raw, *image, cv::COLOR_RGB2BGR);
  else
    *image = raw.clone();
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", *image, png, {cv::IMWRITE_PNG_COMPRESSION, options_.png_compression})) {
    return Internal(who + ": PNG encoding failed");
  }
  *extension = "png";
  return png;
}

Result<StoredFrameInfo> CaptureDataset::StoreFrame(const Frame& frame,
                                                   const FrameContext& context) {
  if (HasVerifiedFrame(context.view)) {
    return FailedPrecondition("view " + std::to_string(context.view) +
                              " already has a verified frame; it is kept");
  }
  StoredFrameInfo info;
  std::string extension;
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                      EncodeForStorage(frame, context, &info.image, &extension));
  const std::string sha = Sha256Hex(bytes.data(), bytes.size());
  char name[32];
  std::snprintf(name, sizeof name, "%03d_", context.view);
  const std::string file =
      "frames/" + std::string(name) + FileNamePart(frame.camera_serial) + "." + extension;
  info.path = dir_ + "/" + file;
  if (!PathIsInside(info.path, dir_))
    return Internal(info.path + ": frame path outside the capture folder");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (options_.simulated_full_after_frames >= 0 &&
        frames_written_ >= options_.simulated_full_after_frames) {
      return IoError(dir_ + ": no space left on device (simulated disk full) while writing " +
                     file + ": free space, then run the capture again with --resume");
    }
    ++frames_written_;
  }
  HR_RETURN_IF_ERROR(WriteFileAtomic(info.path, bytes.data(), bytes.size(), [](const char* stage) {
    CrashPoint((std::string("frame_") + stage).c_str());
  }));
  CrashPoint("frame_before_journal");
  info.record = {{"event", "frame_stored"},
                 {"view", context.view},
                 {"stop", context.stop},
                 {"camera", context.camera_name},
                 {"serial", frame.camera_serial},
                 {"file", file},
                 {"bytes", bytes.size()},
                 {"sha256", sha},
                 {"width_px", info.image.cols},
                 {"height_px", info.image.rows},
                 {"pixel_format", PixelFormatName(frame.format)},
                 {"exposure_s", frame.exposure_s},
                 {"gain_db", frame.gain_db},
                 {"trigger_time_ns", frame.trigger_time_ns},
                 {"received_time_ns", frame.received_time_ns},
                 {"angle_commanded_deg", context.angle_commanded_deg},
                 {"angle_measured_deg", context.angle_measured_deg}};
  std::lock_guard<std::mutex> lock(mutex_);
  HR_RETURN_IF_ERROR(AppendLocked(info.record));
  verified_[context.view] = info.record;
  HR_RETURN_IF_ERROR(WriteManifestLocked(last_status_));
  return info;
}

bool CaptureDataset::HasVerifiedFrame(int view) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return verified_.count(view) > 0;
}

std::vector<nlohmann::json> CaptureDataset::VerifiedFrames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<nlohmann::json> out;
  for (const auto& [view, r] : verified_) out.push_back(r);
  return out;
}

int CaptureDataset::VerifiedFrameCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(verified_.size());
}

uint64_t CaptureDataset::BytesStored() const {
  std::lock_guard<std::mutex> lock(mutex_);
  uint64_t total = 0;
  for (const auto& [view, r] : verified_) total += r.at("bytes").get<uint64_t>();
  return total;
}

Result<uint64_t> CaptureDataset::FreeBytes() const {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (options_.simulated_full_after_frames >= 0 &&
        frames_written_ >= options_.simulated_full_after_frames)
      return 0;
  }
  struct statvfs st {};
  if (::statvfs(dir_.c_str(), &st) != 0)
    return IoError(dir_ + ": cannot read the free space (" + std::strerror(errno) + ")");
  return static_cast<uint64_t>(st.f_bavail) * st.f_frsize;
}

void CaptureDataset::SetPlanSummary(int views_planned, const std::string& subject,
                                    const std::string& rig_name) {
  std::lock_guard<std::mutex> lock(mutex_);
  views_planned_ = views_planned;
  subject_ = subject;
  rig_name_ = rig_name;
}

Status CaptureDataset::WriteManifest(const std::string& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  return WriteManifestLocked(status);
}

Status CaptureDataset::WriteManifestLocked(const std::string& status) {
  last_status_ = status;
  nlohmann::json frames = nlohmann::json::array();
  uint64_t bytes = 0;
  int faults = 0, sessions = 0;
  for (const auto& [view, r] : verified_) {
    frames.push_back({{"view", view},
                      {"serial", r["serial"]},
                      {"camera", r["camera"]},
                      {"file", r["file"]},
                      {"bytes", r["bytes"]},
                      {"sha256", r["sha256"]},
                      {"stop", r["stop"]},
                      {"angle_measured_deg", r["angle_measured_deg"]}});
    bytes += r.at("bytes").get<uint64_t>();
  }
  for (const auto& r : records_) {
    const std::string event = r.value("event", "");
    faults += event == "fault" ? 1 : 0;
    sessions += event == "session_start" ? 1 : 0;
  }
  const nlohmann::json manifest = {{"format", "hairrig-capture"},
                                   {"version", 1},
                                   {"subject", subject_},
                                   {"rig", rig_name_},
                                   {"status", status},
                                   {"views_planned", views_planned_},
                                   {"views_completed", verified_.size()},
                                   {"bytes", bytes},
                                   {"faults", faults},
                                   {"sessions", sessions},
                                   {"journal_records", records_.size()},
                                   {"updated_utc", UtcNow()},
                                   {"frames", frames}};
  const std::string text = manifest.dump(2) + "\n";
  return WriteFileAtomic(dir_ + "/" + kManifest, text.data(), text.size(), [](const char* stage) {
    if (std::string(stage) == "half_written") CrashPoint("manifest_half_written");
  });
}

}  // namespace hairrig
