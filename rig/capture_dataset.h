// The capture dataset (docs/design.md section 4): one folder per capture.
//
//   <capture>/rig.yaml          the rig config as used (snapshot)
//   <capture>/capture.json      written once at creation: format version, creation time,
//                               the folder the config's relative paths resolve against
//   <capture>/journal.jsonl     append-only, one JSON record per line, fsync'd
//   <capture>/manifest.json     state derived from the journal, rewritten atomically
//   <capture>/frames/NNN_<serial>.<ext>   written atomically (temporary + fsync + rename)
//   <capture>/quarantine/       files found on resume that no journal record vouches for
//
// Every record has "event", "seq" (from 0 over the capture's life) and
// "time_utc". Events: session_start, view_planned, position_reached,
// frame_stored (view, serial, file, bytes, sha256, exposure, timestamps),
// fault, session_end, journal_repaired, file_quarantined, partial_removed.
// The records later sessions read back are typed in rig/journal_records.h.
//
// A frame counts only when its frame_stored record is in the journal, and it is
// verified only when the file's size and SHA-256 match that record. Resume keeps
// verified frames and never writes over them. No symlink is followed for
// writing: a capture whose journal.jsonl, frames/, quarantine/ or
// ground_truth/ is a symlink is refused. Thread-safe: several cameras'
// collectors store frames at once.
//
// Every file write (frames, journal records, manifest, rig.yaml,
// capture.json, and the other files of the folder through WriteFile) and the
// free-space reading go through the dataset's CaptureStorage
// (core/capture_storage.h): the file system unless the caller gives another.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/capture_storage.h"
#include "core/status.h"
#include "drivers/camera.h"
#include "rig/journal_records.h"

namespace hairrig {

struct DatasetOptions {
  int png_compression = 1;  // raw frames are stored as PNG, 0-9
  // Bytes a frame must leave free on the capture's disk (the rig config's
  // storage.min_free_mb): StoreFrame refuses a frame that would leave less,
  // WriteFile any other file.
  uint64_t min_free_bytes = 0;

  // InvalidArgument naming png_compression outside 0..9 (every min_free_bytes is valid).
  Status Check() const;
};

// What the sequencer knows about a frame beyond the frame itself.
struct FrameContext {
  int view = 0;
  int stop = 0;
  std::string camera_name;
  double angle_commanded_deg = 0;
  double angle_measured_deg = 0;
  int expected_width_px = 0;  // 0: not checked
  int expected_height_px = 0;
};

struct StoredFrameInfo {
  FrameRecord record;  // the frame_stored journal record
  std::string path;    // absolute path of the frame file
  cv::Mat image;       // decoded pixels (BGR or single channel), for frame sinks
};

// What OpenForResume found and did.
struct ResumeReport {
  int frames_verified = 0;
  std::vector<std::string> quarantined;      // files moved to quarantine/, with why
  std::vector<std::string> partial_removed;  // temporary files of interrupted writes
  size_t journal_bytes_dropped = 0;          // a record cut short by the interruption
};

class CaptureDataset {
 public:
  // Creates `dir` (and its parents; FailedPrecondition if `dir` exists) with
  // the config snapshot, capture.json (metadata with its creation time) and
  // an empty journal. `storage` null: DefaultCaptureStorage(), the file system.
  // On failure (IoError: a full disk) the files it made and `dir` are removed,
  // so that `dir` can be given again; except when another process took the
  // new folder over (its journal locked: FailedPrecondition), which keeps it.
  // InvalidArgument for bad options (DatasetOptions::Check), before anything is made.
  static Result<std::unique_ptr<CaptureDataset>> Create(
      const std::string& dir, const std::string& config_text, CaptureMetadata metadata,
      const DatasetOptions& options, std::shared_ptr<CaptureStorage> storage = nullptr);
  // Opens an interrupted (or finished) capture: takes the journal's lock,
  // drops a journal record cut short, verifies every stored frame against its
  // record (VerifiedFrames), moves unvouched files in frames/ to quarantine/
  // and deletes temporaries of interrupted writes. FailedPrecondition for a
  // symlinked journal.jsonl, frames/, quarantine/ or ground_truth/ or another
  // process writing the capture; CorruptData naming file, line and field for
  // a damaged capture.json or journal record. A missing frames/ is made anew.
  // The repair's journal records are written through `storage` (null: the
  // file system). InvalidArgument for bad options (DatasetOptions::Check).
  static Result<std::unique_ptr<CaptureDataset>> OpenForResume(
      const std::string& dir, const DatasetOptions& options, ResumeReport* report,
      std::shared_ptr<CaptureStorage> storage = nullptr);
  ~CaptureDataset();

  const std::string& dir() const { return dir_; }
  std::string ConfigSnapshotPath() const { return dir_ + "/rig.yaml"; }
  // Where the dataset writes; also for other files of the capture folder.
  CaptureStorage& storage() const { return *storage_; }
  const CaptureMetadata& metadata() const { return metadata_; }  // capture.json
  // Records of earlier sessions (OpenForResume) and this one, in order.
  std::vector<nlohmann::json> Records() const;

  // Appends one record (fills seq and time_utc) and fsyncs the journal.
  Status Append(nlohmann::json record);
  // Journals the plan's view_planned records in a new capture. In a resumed
  // one, checks them against the journal's: FailedPrecondition naming the
  // first view that differs when the plan (the rig.yaml snapshot) changed, or
  // gained views after frames were stored; journals the views an interrupted
  // start left out.
  Status JournalPlan(const std::vector<PlannedViewRecord>& plan);
  // Checks the frame (raw: byte count matches the geometry; encoded: decodes,
  // right size), encodes raw frames as PNG, hashes, checks the free space
  // (CheckFreeSpace), writes atomically, journals frame_stored and rewrites
  // the manifest. CorruptData for a bad frame, FailedPrecondition if the view
  // already has a verified frame, IoError for a frame that would leave less
  // than min_free_bytes free and for storage failures (a write's IoError names
  // the file and the errno: "No space left on device" on a full disk).
  Result<StoredFrameInfo> StoreFrame(const Frame& frame, const FrameContext& context);

  bool HasVerifiedFrame(int view) const;
  // frame_stored records of the verified frames, in view order.
  std::vector<FrameRecord> VerifiedFrames() const;
  int VerifiedFrameCount() const;
  uint64_t BytesStored() const;  // of verified frames
  // Free bytes on the capture's disk, as its storage reports them.
  Result<uint64_t> FreeBytes() const;
  // Ok when `bytes` more (0: none), beside the files being written, leave at
  // least options.min_free_bytes free on the capture's disk, with room left
  // for what a session journals and rewrites after a check (the manifest's
  // size plus 16 KiB of journal records), so that those never take the disk
  // below the limit either. IoError naming the folder, the free MB and the
  // limit (storage.min_free_mb) otherwise, or why the free space is unknown.
  Status CheckFreeSpace(uint64_t bytes) const;
  // Writes a file of the capture folder other than a frame (the contact
  // sheet, the simulated rig's ground truth) atomically through the storage,
  // once the check a frame passes (CheckFreeSpace, counting the files being
  // written) allows its `size` bytes: IoError naming the folder, the file,
  // the free MB and storage.min_free_mb when it would leave less, else the
  // write's Status (an IoError naming `path` and the errno on a full disk).
  Status WriteFile(const std::string& path, const void* data, size_t size);

  // Manifest fields the sequencer owns.
  void SetPlanSummary(int views_planned, const std::string& subject, const std::string& rig_name);
  Status WriteManifest(const std::string& status);

 private:
  CaptureDataset(std::string dir, DatasetOptions options, std::shared_ptr<CaptureStorage> storage);
  Status OpenJournal();
  Status AppendLocked(nlohmann::json record);
  Status WriteManifestLocked(const std::string& status);
  Status Repair(ResumeReport* report);
  // CheckFreeSpace, then counts `bytes` as written until ReleaseSpace, so
  // that files written at once cannot pass the check together. `what` names
  // them in the refusal ("a frame of 2.100 MB").
  Status ReserveSpace(uint64_t bytes, const std::string& what);
  void ReleaseSpace(uint64_t bytes);
  Status CheckFreeSpaceLocked(uint64_t bytes, const std::string& what) const;
  Status ClearFramesFolder(ResumeReport* report);
  Result<std::vector<uint8_t>> EncodeForStorage(const Frame& frame, const FrameContext& context,
                                                cv::Mat* image, std::string* extension) const;

  std::string dir_;
  DatasetOptions options_;
  std::shared_ptr<CaptureStorage> storage_;  // never null
  CaptureMetadata metadata_;
  int journal_fd_ = -1;
  mutable std::mutex mutex_;
  mutable std::mutex space_mutex_;  // guards reserved_bytes_; taken without mutex_
  uint64_t reserved_bytes_ = 0;     // files being written
  // The size of the manifest last written: CheckFreeSpace keeps room for its next version.
  std::atomic<uint64_t> manifest_bytes_{0};
  std::vector<nlohmann::json> records_;
  std::map<int, FrameRecord> verified_;       // view -> frame_stored record
  std::map<int, PlannedViewRecord> planned_;  // view -> view_planned record
  int64_t next_seq_ = 0;
  int frames_written_ = 0;  // frame_stored records over the capture's life
  int views_planned_ = 0;
  std::string subject_, rig_name_, last_status_ = "in_progress";
};

// The records of a capture's journal.jsonl, read only; record i is line i + 1.
// A last line without its newline (a record cut short by an interruption) is
// left out and its size is put in *cut_short_bytes; a complete line that is
// not a JSON object with a string "event" and an integer "seq" in [0, 2^50] is
// CorruptData naming the file, line and field.
Result<std::vector<nlohmann::json>> ReadJournalRecords(const std::string& journal_path,
                                                       size_t* cut_short_bytes = nullptr);

// capture.json of a capture folder (a regular file; CorruptData naming it and the field).
Result<CaptureMetadata> ReadCaptureMetadata(const std::string& capture_dir);
// ReadCaptureMetadata of a capture to resume, read only: NotFound (nothing to
// resume) when `capture_dir` has no journal.jsonl. Its config snapshot is
// <capture_dir>/rig.yaml, relative paths resolving against metadata.config_dir.
Result<CaptureMetadata> ReadResumableCapture(const std::string& capture_dir);

// The view_planned records of a journal, by view. CorruptData naming the line
// and field for a damaged record or a view planned twice differently.
Result<std::map<int, PlannedViewRecord>> PlannedViews(const std::string& journal_path,
                                                      const std::vector<nlohmann::json>& records);

// Whether a frame file matches what vouches for it: `file` (relative to the
// capture folder) resolved with its symlinks stays inside the folder, is a
// regular file of `bytes` bytes and has SHA-256 `sha256`. The resolved path,
// the file that was checked, which is the one to read; else the Status says
// why not, naming the file.
Result<std::string> VerifyFrameFile(const std::string& capture_dir, const std::string& file,
                                    uint64_t bytes, const std::string& sha256);

// One view's frame as a record vouches for it, for CheckDistinctContent.
struct FrameContent {
  std::string sha256;
  // Name the record and its SHA-256 in messages: "<capture>/journal.jsonl:
  // line 12" and "<capture>/journal.jsonl: line 12: field 'sha256'".
  std::string record;
  std::string sha256_field;
};
// Two exposures never give the same bytes: one frame vouched for by two views'
// records is a record (and its file) copied onto another view. CorruptData
// "<sha256_field>: view 5 has the same frame content as view 2 (<record>);
// <advice>" for the first view (by number) whose SHA-256 an earlier view
// has; Ok when every view's differs. Resume, replay (VerifiedFrames) and the
// stages after capture (rig/manifest_frames.h ReadManifestFrames) refuse such a
// capture alike.
Status CheckDistinctContent(const std::map<int, FrameContent>& frames, const std::string& advice);

// The frames of a capture that count, decided in one way for resume and
// replay: per view, the last frame_stored record of `records` (the capture's
// journal), if its file verifies (VerifyFrameFile). CorruptData naming the
// journal line and field for a damaged record (FrameRecord::FromJson), a frame
// of a view no view_planned record plans, of another camera than the one
// planned for its view, or with the same SHA-256 as another view's frame (a
// record copied onto another view, its file copied too).
Result<std::map<int, FrameRecord>> VerifiedFrames(const std::string& capture_dir,
                                                  const std::vector<nlohmann::json>& records);

// The free-space rule every file of a capture honours (storage.min_free_mb),
// CaptureDataset's check and that of the stages a capture command runs after
// it: Ok when `bytes` more (0: none), beside `reserved` bytes being written,
// leave at least `min_free` + `beside` of the `free` bytes on the disk holding
// `dir` (`beside`: room kept for the journal and manifest written after the
// check). IoError naming `dir`, the free MB, `what` ("a frame of 2.100 MB")
// and the limit otherwise.
Status CheckRoomOnDisk(const std::string& dir, uint64_t free, uint64_t reserved, uint64_t bytes,
                       const std::string& what, uint64_t min_free, uint64_t beside);

// Current UTC time as ISO 8601 with milliseconds ("2026-11-22T10:04:05.123Z").
std::string UtcNow();

}  // namespace hairrig
