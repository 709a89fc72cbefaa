#include "rig/capture_dataset.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "core/file_util.h"
#include "core/json_file.h"
#include "core/sha256.h"
#include "drivers/frame_image.h"
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
constexpr int64_t kMaxSeq = int64_t{1} << 50;  // far beyond any capture's record count
// Journal records a session may append after a free-space check (a frame's
// frame_stored, faults, session_end: each well under 1 KiB), and the growth
// of the manifest by a frame's entry.
constexpr uint64_t kJournalRoomBytes = 16384;
constexpr const char* kAlteredAdvice =
    "the journal was altered: keep a copy of it, then correct or remove that line by hand";

// "0.998 MB", "9.500 MB", "200.0 MB": three decimals below 10 MB.
std::string MegabytesText(uint64_t bytes) {
  char text[48];
  const double mb = static_cast<double>(bytes) / 1e6;
  std::snprintf(text, sizeof text, mb < 10 ? "%.3f MB" : "%.1f MB", mb);
  return text;
}

bool Exists(const fs::path& path) {
  std::error_code ec;
  return fs::symlink_status(path, ec).type() != fs::file_type::not_found;
}

// Moves `file` (whatever it is; a symlink is moved, not followed) into
// <dir>/quarantine/ under a name not yet taken.
Result<std::string> Quarantine(const std::string& dir, const fs::path& file) {
  const fs::path q = fs::path(dir) / "quarantine";
  std::error_code ec;
  fs::create_directories(q, ec);
  fs::path target = q / file.filename();
  for (int n = 1; Exists(target); ++n)
    target = q / (file.filename().string() + "." + std::to_string(n));
  fs::rename(file, target, ec);
  if (ec) return IoError(file.string() + ": cannot move it to quarantine/ (" + ec.message() + ")");
  return target.string();
}

// Resume writes into these; none may lead elsewhere.
Status RefuseSymlinks(const std::string& dir) {
  for (const char* name : {kJournal, "frames", "quarantine", "ground_truth"}) {
    const fs::path path = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(path, ec))) {
      return FailedPrecondition(
          path.string() + " is a symlink (to " + fs::read_symlink(path, ec).string() +
          "); hairrig writes only into the capture folder itself: replace it by the " +
          (std::string(name) == kJournal ? "file" : "folder") + " it points to, then resume");
    }
  }
  return Status::Ok();
}

Status CheckAgainstPlan(const FrameRecord& f, const std::map<int, PlannedViewRecord>& planned,
                        const std::string& where) {
  const auto plan = planned.find(f.view);
  if (plan == planned.end()) {
    return CorruptData(where + ": field 'view': no view_planned record plans view " +
                       std::to_string(f.view) + "; " + kAlteredAdvice);
  }
  if (plan->second.serial != f.serial) {
    return CorruptData(where + ": field 'serial': view " + std::to_string(f.view) +
                       " is planned for camera " + plan->second.serial + ", the record names " +
                       f.serial + "; " + kAlteredAdvice);
  }
  return Status::Ok();
}

}  // namespace

Result<std::vector<nlohmann::json>> ReadJournalRecords(const std::string& journal_path,
                                                       size_t* cut_short_bytes) {
  HR_ASSIGN_OR_RETURN(const std::string text, ReadFileText(journal_path, kMaxJsonFileBytes));
  std::vector<nlohmann::json> records;
  size_t line_start = 0;
  for (size_t end = text.find('\n'); end != std::string::npos; end = text.find('\n', line_start)) {
    const std::string where = JournalLine(journal_path, records.size());
    Result<nlohmann::json> record =
        ParseJson(std::string_view(text).substr(line_start, end - line_start), where);
    if (!record.ok())
      return CorruptData(record.status().message() + " and is not the last line; " +
                         kAlteredAdvice);
    const JsonObject envelope(*record, where);
    envelope.String("event");
    envelope.Integer("seq", {.min = 0, .max = kMaxSeq});
    if (!envelope.ok()) return CorruptData(envelope.status().message() + "; " + kAlteredAdvice);
    records.push_back(std::move(record).value());
    line_start = end + 1;
  }
  if (cut_short_bytes) *cut_short_bytes = text.size() - line_start;
  return records;
}

Result<CaptureMetadata> ReadCaptureMetadata(const std::string& capture_dir) {
  const std::string path = (fs::path(capture_dir) / kMetadata).string();
  HR_ASSIGN_OR_RETURN(const nlohmann::json j,
                      ReadJsonFile(path, "is " + capture_dir + " a capture folder?"));
  return CaptureMetadata::FromJson(j, path);
}

Result<CaptureMetadata> ReadResumableCapture(const std::string& capture_dir) {
  if (!Exists(fs::path(capture_dir) / kJournal)) {
    return NotFound(capture_dir + " is not a capture folder (no " + kJournal +
                    "): nothing to resume");
  }
  return ReadCaptureMetadata(capture_dir);
}

Result<std::map<int, PlannedViewRecord>> PlannedViews(const std::string& journal_path,
                                                      const std::vector<nlohmann::json>& records) {
  std::map<int, PlannedViewRecord> planned;
  for (size_t i = 0; i < records.size(); ++i) {
    if (JournalEvent(records[i]) != "view_planned") continue;
    const std::string where = JournalLine(journal_path, i);
    Result<PlannedViewRecord> read = PlannedViewRecord::FromJson(records[i], where);
    if (!read.ok()) return CorruptData(read.status().message() + "; " + kAlteredAdvice);
    const PlannedViewRecord& view = *read;
    const auto [it, added] = planned.emplace(view.view, view);
    if (!added && !(it->second == view)) {
      return CorruptData(where + ": plans " + view.Describe() + ", an earlier line " +
                         it->second.Describe() + "; " + kAlteredAdvice);
    }
  }
  return planned;
}

Result<std::string> VerifyFrameFile(const std::string& capture_dir, const std::string& file,
                                    uint64_t bytes, const std::string& sha256) {
  HR_ASSIGN_OR_RETURN(const std::string path,
                      ResolveInside((fs::path(capture_dir) / file).string(), capture_dir));
  uint64_t file_bytes = 0;
  const Result<std::string> actual = Sha256OfFile(path, bytes, &file_bytes);
  if (actual.status().code() == StatusCode::kOutOfRange)
    return CorruptData(path + ": larger than the " + std::to_string(bytes) +
                       " bytes its record gives");
  if (!actual.ok()) return actual.status();
  if (file_bytes != bytes) {
    return CorruptData(path + ": " + std::to_string(file_bytes) + " bytes, its record gives " +
                       std::to_string(bytes));
  }
  if (*actual != sha256) return CorruptData(path + ": its SHA-256 does not match its record");
  return path;
}

Status CheckDistinctContent(const std::map<int, FrameContent>& frames, const std::string& advice) {
  // Two exposures never give the same bytes: one frame vouched for by two
  // views' records is a record (and its file) copied onto another view.
  std::map<std::string, int> view_of_content;
  for (const auto& [view, frame] : frames) {
    const auto [other, inserted] = view_of_content.emplace(frame.sha256, view);
    if (inserted) continue;
    return CorruptData(frame.sha256_field + ": view " + std::to_string(view) +
                       " has the same frame content as view " + std::to_string(other->second) +
                       " (" + frames.at(other->second).record + "); " + advice);
  }
  return Status::Ok();
}

Result<std::map<int, FrameRecord>> VerifiedFrames(const std::string& capture_dir,
                                                  const std::vector<nlohmann::json>& records) {
  const std::string journal = (fs::path(capture_dir) / kJournal).string();
  HR_ASSIGN_OR_RETURN(const auto planned, PlannedViews(journal, records));
  std::map<int, FrameRecord> claimed;  // the last record per view
  std::map<int, size_t> claimed_line;
  for (size_t i = 0; i < records.size(); ++i) {
    if (JournalEvent(records[i]) != "frame_stored") continue;
    const std::string where = JournalLine(journal, i);
    Result<FrameRecord> frame = FrameRecord::FromJson(records[i], where);
    if (!frame.ok()) return CorruptData(frame.status().message() + "; " + kAlteredAdvice);
    HR_RETURN_IF_ERROR(CheckAgainstPlan(*frame, planned, where));
    claimed_line[frame->view] = i;
    claimed[frame->view] = std::move(frame).value();
  }
  std::map<int, FrameContent> contents;
  for (const auto& [view, frame] : claimed) {
    const std::string line = JournalLine(journal, claimed_line[view]);
    contents[view] = {frame.sha256, line, line + ": field 'sha256'"};
  }
  HR_RETURN_IF_ERROR(CheckDistinctContent(contents, kAlteredAdvice));
  std::map<int, FrameRecord> verified;
  for (auto& [view, frame] : claimed) {
    if (VerifyFrameFile(capture_dir, frame.file, frame.bytes, frame.sha256).ok())
      verified.emplace(view, std::move(frame));
  }
  return verified;
}

CaptureDataset::CaptureDataset(std::string dir, DatasetOptions options,
                               std::shared_ptr<CaptureStorage> storage)
    : dir_(std::move(dir)),
      options_(options),
      storage_(storage ? std::move(storage) : DefaultCaptureStorage()) {}

CaptureDataset::~CaptureDataset() {
  if (journal_fd_ >= 0) ::close(journal_fd_);
}

Status CaptureDataset::OpenJournal() {
  const std::string path = dir_ + "/" + kJournal;
  HR_ASSIGN_OR_RETURN(journal_fd_, OpenRegularFileForAppend(path));
  // One writer per capture: a second hairrig on the same folder is refused.
  if (::flock(journal_fd_, LOCK_EX | LOCK_NB) != 0) {
    return FailedPrecondition(
        dir_ + " is being written by another hairrig process; wait for it to finish");
  }
  return Status::Ok();
}

Status DatasetOptions::Check() const {
  if (png_compression < 0 || png_compression > 9) {
    return InvalidArgument("storage.png_compression must lie in 0..9, got " +
                           std::to_string(png_compression));
  }
  return Status::Ok();
}

Result<std::unique_ptr<CaptureDataset>> CaptureDataset::Create(
    const std::string& dir, const std::string& config_text, CaptureMetadata metadata,
    const DatasetOptions& options, std::shared_ptr<CaptureStorage> storage) {
  HR_RETURN_IF_ERROR(options.Check());
  std::error_code ec;
  if (Exists(dir)) {
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
  auto dataset = std::unique_ptr<CaptureDataset>(new CaptureDataset(
      fs::absolute(dir).lexically_normal().string(), options, std::move(storage)));
  const Status created = [&]() -> Status {
    CaptureStorage& out = *dataset->storage_;
    HR_RETURN_IF_ERROR(out.WriteFileAtomic(dataset->ConfigSnapshotPath(), config_text.data(),
                                           config_text.size(), {}));
    metadata.created_utc = UtcNow();
    const std::string metadata_text = metadata.ToJson().dump(2) + "\n";
    HR_RETURN_IF_ERROR(out.WriteFileAtomic(dataset->dir_ + "/" + kMetadata, metadata_text.data(),
                                           metadata_text.size(), {}));
    dataset->metadata_ = std::move(metadata);
    HR_RETURN_IF_ERROR(dataset->OpenJournal());
    return SyncFolder(parent.string());
  }();
  if (!created.ok()) {
    const fs::path made = dataset->dir_;
    dataset.reset();
    // FailedPrecondition: OpenJournal found the journal locked by another
    // process, which has taken the folder over; it stays as it is. Else (a
    // full disk, say) what this call made goes, the folder last and only once
    // empty, so that the same folder can be given again.
    if (created.code() != StatusCode::kFailedPrecondition) {
      for (const char* name : {kJournal, kMetadata, "rig.yaml", "frames"})
        fs::remove(made / name, ec);
      fs::remove(made, ec);
    }
    return created;
  }
  return dataset;
}

Result<std::unique_ptr<CaptureDataset>> CaptureDataset::OpenForResume(
    const std::string& dir, const DatasetOptions& options, ResumeReport* report,
    std::shared_ptr<CaptureStorage> storage) {
  HR_RETURN_IF_ERROR(options.Check());
  auto dataset = std::unique_ptr<CaptureDataset>(new CaptureDataset(
      fs::absolute(dir).lexically_normal().string(), options, std::move(storage)));
  HR_ASSIGN_OR_RETURN(dataset->metadata_, ReadResumableCapture(dataset->dir_));
  ResumeReport local;
  HR_RETURN_IF_ERROR(dataset->Repair(report ? report : &local));
  return dataset;
}

// Takes the journal's lock, reads it, cuts a record left half-written,
// verifies frames and clears out what no record vouches for.
Status CaptureDataset::Repair(ResumeReport* report) {
  HR_RETURN_IF_ERROR(RefuseSymlinks(dir_));
  HR_RETURN_IF_ERROR(OpenJournal());
  const std::string journal_path = dir_ + "/" + kJournal;
  HR_ASSIGN_OR_RETURN(records_, ReadJournalRecords(journal_path, &report->journal_bytes_dropped));
  HR_ASSIGN_OR_RETURN(planned_, PlannedViews(journal_path, records_));
  HR_ASSIGN_OR_RETURN(verified_, ::hairrig::VerifiedFrames(dir_, records_));
  struct stat journal {};
  if (report->journal_bytes_dropped > 0 &&
      (::fstat(journal_fd_, &journal) != 0 ||
       ::ftruncate(journal_fd_,
                   journal.st_size - static_cast<off_t>(report->journal_bytes_dropped)) != 0)) {
    return IoError(journal_path + ": cannot cut the interrupted record (" + std::strerror(errno) +
                   ")");
  }
  for (const auto& r : records_) {
    next_seq_ = std::max<int64_t>(next_seq_, r.value("seq", int64_t{0}) + 1);  // checked on reading
    if (JournalEvent(r) == "frame_stored") ++frames_written_;
  }
  if (report->journal_bytes_dropped > 0) {
    HR_RETURN_IF_ERROR(AppendLocked({{"event", "journal_repaired"},
                                     {"bytes_dropped", report->journal_bytes_dropped},
                                     {"why", "a record was cut short by the interruption"}}));
  }
  report->frames_verified = static_cast<int>(verified_.size());
  HR_RETURN_IF_ERROR(ClearFramesFolder(report));
  // Temporaries of interrupted atomic writes (files) in the capture folder itself.
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    if (entry.path().filename().string().find(".tmp.") != std::string::npos &&
        !entry.is_directory(ec))
      fs::remove(entry.path(), ec);
  }
  return Status::Ok();
}

// frames/ keeps the verified frames only: temporaries of interrupted writes
// are deleted, anything else moves to quarantine/. A missing frames/ is made.
Status CaptureDataset::ClearFramesFolder(ResumeReport* report) {
  const fs::path frames = fs::path(dir_) / "frames";
  std::error_code ec;
  if (!Exists(frames)) fs::create_directory(frames, ec);
  if (!fs::is_directory(fs::symlink_status(frames, ec)))
    return FailedPrecondition(frames.string() + " is not a folder: move it away, then resume");
  std::set<std::string> kept;
  for (const auto& [view, r] : verified_) kept.insert(fs::path(r.file).filename().string());
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(frames, ec)) entries.push_back(entry.path());
  if (ec) return IoError(frames.string() + ": cannot list the folder (" + ec.message() + ")");
  for (const fs::path& entry : entries) {
    const std::string name = entry.filename().string();
    if (kept.count(name)) continue;
    if (name.find(".tmp.") != std::string::npos &&
        fs::is_regular_file(fs::symlink_status(entry, ec))) {
      fs::remove(entry, ec);
      report->partial_removed.push_back(name);
      HR_RETURN_IF_ERROR(AppendLocked({{"event", "partial_removed"}, {"file", "frames/" + name}}));
      continue;
    }
    HR_ASSIGN_OR_RETURN(std::string moved, Quarantine(dir_, entry));
    const std::string why = "no journal record vouches for it (or its checksum does not match)";
    report->quarantined.push_back(name + ": " + why);
    HR_RETURN_IF_ERROR(
        AppendLocked({{"event", "file_quarantined"},
                      {"file", "frames/" + name},
                      {"moved_to", fs::path(moved).lexically_relative(dir_).string()},
                      {"why", why}}));
  }
  return Status::Ok();
}

Status CaptureDataset::JournalPlan(const std::vector<PlannedViewRecord>& plan) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool frames_stored = frames_written_ > 0;
  std::map<int, const PlannedViewRecord*> wanted;
  for (const PlannedViewRecord& v : plan) wanted[v.view] = &v;
  const std::string advice =
      ": the plan of a capture cannot change once it started. Restore the plan in " +
      ConfigSnapshotPath() +
      " (journal.jsonl lists the original view_planned records), or start a new capture with "
      "another --out";
  for (const auto& [view, journaled] : planned_) {
    const auto now = wanted.find(view);
    if (now == wanted.end())
      return FailedPrecondition("the capture was started with " + journaled.Describe() +
                                ", now not planned" + advice);
    if (!(*now->second == journaled)) {
      return FailedPrecondition("the capture was started with " + journaled.Describe() +
                                ", now planned as " + now->second->Describe() + advice);
    }
  }
  for (const PlannedViewRecord& v : plan) {
    if (planned_.count(v.view)) continue;
    if (frames_stored) return FailedPrecondition(v.Describe() + " was added to the plan" + advice);
    HR_RETURN_IF_ERROR(AppendLocked(v.ToJson()));
    planned_[v.view] = v;
  }
  return Status::Ok();
}

Status CaptureDataset::Append(nlohmann::json record) {
  std::lock_guard<std::mutex> lock(mutex_);
  return AppendLocked(std::move(record));
}

Status CaptureDataset::AppendLocked(nlohmann::json record) {
  record["seq"] = next_seq_;
  record["time_utc"] = UtcNow();
  const std::string line = record.dump() + "\n";
  HR_RETURN_IF_ERROR(
      storage_->AppendDurably(journal_fd_, dir_ + "/" + kJournal, line.data(), line.size(),
                              [](const char*) { CrashPoint("journal_half_written"); }));
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
  if (frame.format != PixelFormat::kEncoded && frame.width_px > 0 && frame.height_px > 0 &&
      size_known &&
      (frame.width_px != context.expected_width_px ||
       frame.height_px != context.expected_height_px)) {
    return CorruptData(who + ": frame is " + std::to_string(frame.width_px) + "x" +
                       std::to_string(frame.height_px) + ", the camera's sensor is " +
                       std::to_string(context.expected_width_px) + "x" +
                       std::to_string(context.expected_height_px));
  }
  Result<cv::Mat> decoded = FrameImage(frame);
  if (!decoded.ok()) return CorruptData(who + ": " + decoded.status().message());
  *image = std::move(*decoded);
  if (frame.format == PixelFormat::kEncoded) {
    if (size_known &&
        (image->cols != context.expected_width_px || image->rows != context.expected_height_px)) {
      return CorruptData(who + ": decodes to " + std::to_string(image->cols) + "x" +
                         std::to_string(image->rows) + ", expected " +
                         std::to_string(context.expected_width_px) + "x" +
                         std::to_string(context.expected_height_px));
    }
    *extension = FileNamePart(frame.encoding);
    return frame.data;
  }
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
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto plan = planned_.find(context.view);
    if (plan == planned_.end())
      return Internal("view " + std::to_string(context.view) +
                      " is not in the journaled plan (JournalPlan)");
    if (plan->second.serial != frame.camera_serial) {
      return CorruptData("view " + std::to_string(context.view) + " is planned for camera " +
                         plan->second.serial + ", the frame came from " + frame.camera_serial);
    }
  }
  StoredFrameInfo info;
  std::string extension;
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                      EncodeForStorage(frame, context, &info.image, &extension));
  FrameRecord& r = info.record;
  r.view = context.view;
  r.stop = context.stop;
  r.camera = context.camera_name;
  r.serial = frame.camera_serial;
  r.file = FrameFileName(context.view, frame.camera_serial, extension);
  r.bytes = bytes.size();
  r.sha256 = Sha256Hex(bytes.data(), bytes.size());
  r.width_px = info.image.cols;
  r.height_px = info.image.rows;
  r.pixel_format = PixelFormatName(frame.format);
  r.exposure_s = frame.exposure_s;
  r.gain_db = frame.gain_db;
  r.trigger_time_ns = frame.trigger_time_ns;
  r.received_time_ns = frame.received_time_ns;
  r.angle_commanded_deg = context.angle_commanded_deg;
  r.angle_measured_deg = context.angle_measured_deg;
  info.path = dir_ + "/" + r.file;
  HR_RETURN_IF_ERROR(ReserveSpace(bytes.size(), "a frame of " + MegabytesText(bytes.size())));
  const Status written = storage_->WriteFileAtomic(
      info.path, bytes.data(), bytes.size(),
      [](const char* stage) { CrashPoint((std::string("frame_") + stage).c_str()); });
  ReleaseSpace(bytes.size());
  HR_RETURN_IF_ERROR(written);
  CrashPoint("frame_before_journal");
  std::lock_guard<std::mutex> lock(mutex_);
  HR_RETURN_IF_ERROR(AppendLocked(r.ToJson()));
  ++frames_written_;
  verified_[context.view] = r;
  HR_RETURN_IF_ERROR(WriteManifestLocked(last_status_));
  return info;
}

bool CaptureDataset::HasVerifiedFrame(int view) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return verified_.count(view) > 0;
}

std::vector<FrameRecord> CaptureDataset::VerifiedFrames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<FrameRecord> out;
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
  for (const auto& [view, r] : verified_) total += r.bytes;
  return total;
}

Result<uint64_t> CaptureDataset::FreeBytes() const { return storage_->FreeBytes(dir_); }

Status CaptureDataset::CheckFreeSpace(uint64_t bytes) const {
  std::lock_guard<std::mutex> lock(space_mutex_);
  return CheckFreeSpaceLocked(bytes, "a write of " + MegabytesText(bytes));
}

Status CaptureDataset::WriteFile(const std::string& path, const void* data, size_t size) {
  const std::string name = fs::path(path).lexically_relative(dir_).string();
  HR_RETURN_IF_ERROR(ReserveSpace(size, name + " (" + MegabytesText(size) + ")"));
  const Status written = storage_->WriteFileAtomic(path, data, size, {});
  ReleaseSpace(size);
  return written;
}

Status CaptureDataset::ReserveSpace(uint64_t bytes, const std::string& what) {
  std::lock_guard<std::mutex> lock(space_mutex_);
  HR_RETURN_IF_ERROR(CheckFreeSpaceLocked(bytes, what));
  reserved_bytes_ += bytes;
  return Status::Ok();
}

void CaptureDataset::ReleaseSpace(uint64_t bytes) {
  std::lock_guard<std::mutex> lock(space_mutex_);
  reserved_bytes_ -= bytes;
}

Status CaptureDataset::CheckFreeSpaceLocked(uint64_t bytes, const std::string& what) const {
  HR_ASSIGN_OR_RETURN(const uint64_t free, FreeBytes());
  // Files being written by other threads count as written.
  return CheckRoomOnDisk(dir_, free, reserved_bytes_, bytes, what, options_.min_free_bytes,
                         manifest_bytes_.load() + kJournalRoomBytes);
}

Status CheckRoomOnDisk(const std::string& dir, uint64_t free, uint64_t reserved, uint64_t bytes,
                       const std::string& what, uint64_t min_free, uint64_t beside) {
  const uint64_t keep = min_free > UINT64_MAX - beside ? UINT64_MAX : min_free + beside;
  const uint64_t left = free > reserved ? free - reserved : 0;
  if (left >= bytes && left - bytes >= keep) return Status::Ok();
  std::string limit = "the " + MegabytesText(min_free) + " storage.min_free_mb keeps free";
  if (beside > 0) limit += " (beside " + MegabytesText(beside) + " for the journal and manifest)";
  if (bytes == 0) return IoError(dir + ": " + MegabytesText(free) + " free, less than " + limit);
  return IoError(dir + ": " + MegabytesText(free) + " free; " + what + " would leave less than " +
                 limit);
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
                      {"serial", r.serial},
                      {"camera", r.camera},
                      {"file", r.file},
                      {"bytes", r.bytes},
                      {"sha256", r.sha256},
                      {"stop", r.stop},
                      {"angle_measured_deg", r.angle_measured_deg}});
    bytes += r.bytes;
  }
  for (const auto& r : records_) {
    const std::string event = JournalEvent(r);
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
  manifest_bytes_ = text.size();
  return storage_->WriteFileAtomic(dir_ + "/" + kManifest, text.data(), text.size(),
                                   [](const char* stage) {
                                     if (std::string(stage) == "half_written")
                                       CrashPoint("manifest_half_written");
                                   });
}

}  // namespace hairrig
