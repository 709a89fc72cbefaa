#include "rig/capture_dataset.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "core/file_util.h"
#include "core/sha256.h"
#include "rig/replay.h"
#include "sim_hw/quota_storage.h"
#include "tests/support/capture_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using namespace hairrig::testing;

Frame RawFrame(int width, int height, uint8_t value = 90) {
  Frame f;
  f.camera_serial = "CAM-1";
  f.width_px = width;
  f.height_px = height;
  f.format = PixelFormat::kMono8;
  f.data.assign(static_cast<size_t>(width * height), value);
  return f;
}

// Ten views of camera CAM-1, one per stop.
std::vector<PlannedViewRecord> TestPlan() {
  std::vector<PlannedViewRecord> plan;
  for (int v = 0; v < 10; ++v) plan.push_back({v, v, 36.0 * v, "cam", "CAM-1", {{"top", 1.0}}});
  return plan;
}

std::unique_ptr<CaptureDataset> NewDataset(const std::string& name) {
  const std::string dir = FreshDir(name) + "/c";
  CaptureMetadata metadata;
  metadata.config_dir = "/";
  auto d = CaptureDataset::Create(dir, "name: test\n", metadata, {});
  EXPECT_TRUE(d.ok()) << d.status().ToString();
  if (!d.ok()) return nullptr;
  EXPECT_TRUE((*d)->JournalPlan(TestPlan()).ok());
  return std::move(d).value();
}

TEST(CaptureDataset, StoresAVerifiedFrameAndRefusesToOverwriteIt) {
  auto d = NewDataset("dataset_store");
  ASSERT_TRUE(d);
  auto stored = d->StoreFrame(RawFrame(64, 48), {3, 1, "cam", 10, 10.001, 64, 48});
  ASSERT_TRUE(stored.ok()) << stored.status().ToString();
  EXPECT_EQ(stored->record.file, "frames/003_CAM-1.png");
  EXPECT_TRUE(d->HasVerifiedFrame(3));
  const auto again = d->StoreFrame(RawFrame(64, 48, 7), {3, 1, "cam", 10, 10, 64, 48});
  EXPECT_EQ(again.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(VerifiedFramesOnDisk(d->dir()).at(3)["sha256"], stored->record.sha256);
}

TEST(CaptureDataset, BadFramesAreRefusedAndNothingIsWritten) {
  auto d = NewDataset("dataset_bad");
  ASSERT_TRUE(d);
  Frame short_frame = RawFrame(64, 48);
  short_frame.data.resize(100);
  auto r = d->StoreFrame(short_frame, {0, 0, "cam", 0, 0, 64, 48});
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find("CAM-1"), std::string::npos) << r.status().ToString();
  r = d->StoreFrame(RawFrame(32, 48), {1, 0, "cam", 0, 0, 64, 48});
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData) << "a frame of the wrong size";
  Frame garbage = RawFrame(8, 8);
  garbage.format = PixelFormat::kEncoded;
  garbage.encoding = "jpg";
  r = d->StoreFrame(garbage, {2, 0, "cam", 0, 0, 0, 0});
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find("does not decode"), std::string::npos)
      << r.status().ToString();
  EXPECT_TRUE(fs::is_empty(d->dir() + "/frames"));
  EXPECT_EQ(CountEvents(ReadJournal(d->dir()), "frame_stored"), 0);
}

TEST(CaptureDataset, CreateRefusesAnExistingFolder) {
  const std::string dir = FreshDir("dataset_exists");
  auto d = CaptureDataset::Create(dir, "x: 1\n", {}, {});
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.status().message().find("--resume"), std::string::npos);
}

TEST(CaptureDataset, ResumeRepairsWhatAnInterruptionLeft) {
  std::string dir;
  std::string sha_kept;
  {
    auto d = NewDataset("dataset_repair");
    ASSERT_TRUE(d);
    dir = d->dir();
    sha_kept = d->StoreFrame(RawFrame(64, 48, 1), {0, 0, "cam", 0, 0, 64, 48})->record.sha256;
    ASSERT_TRUE(d->StoreFrame(RawFrame(64, 48, 2), {1, 0, "cam", 0, 0, 64, 48}).ok());
  }
  // Frame 1 altered after the fact, an unjournalled file, a temporary, half a record.
  std::ofstream(dir + "/frames/001_CAM-1.png", std::ios::app) << "x";
  std::ofstream(dir + "/frames/002_CAM-1.png") << "complete but never journalled";
  std::ofstream(dir + "/frames/003_CAM-1.png.tmp.99") << "half";
  std::ofstream(dir + "/journal.jsonl", std::ios::app) << "{\"event\":\"frame_sto";
  ResumeReport report;
  auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_TRUE(d.ok()) << d.status().ToString();
  EXPECT_EQ(report.frames_verified, 1);
  EXPECT_TRUE((*d)->HasVerifiedFrame(0));
  EXPECT_FALSE((*d)->HasVerifiedFrame(1));
  EXPECT_GT(report.journal_bytes_dropped, 0u);
  EXPECT_EQ(report.quarantined.size(), 2u);
  EXPECT_EQ(report.partial_removed.size(), 1u);
  EXPECT_TRUE(fs::exists(dir + "/quarantine/001_CAM-1.png"));
  EXPECT_TRUE(fs::exists(dir + "/quarantine/002_CAM-1.png"));
  EXPECT_EQ(VerifiedFramesOnDisk(dir).at(0)["sha256"], sha_kept);
  const auto journal = ReadJournal(dir);
  EXPECT_EQ(CountEvents(journal, "journal_repaired"), 1);
  EXPECT_EQ(CountEvents(journal, "file_quarantined"), 2);
  // The re-shot view 1 is stored anew.
  EXPECT_TRUE((*d)->StoreFrame(RawFrame(64, 48, 2), {1, 0, "cam", 0, 0, 64, 48}).ok());
  // A second writer on the same capture is refused.
  ResumeReport other;
  auto second = CaptureDataset::OpenForResume(dir, {}, &other);
  EXPECT_FALSE(second.ok());
}

TEST(CaptureDataset, AJournalAlteredInTheMiddleIsRefused) {
  std::string dir;
  {
    auto d = NewDataset("dataset_altered");
    ASSERT_TRUE(d);
    dir = d->dir();
    ASSERT_TRUE(d->Append({{"event", "note"}}).ok());
  }
  std::string text;
  {
    std::ifstream in(dir + "/journal.jsonl");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_TRUE(WriteFileAtomic(dir + "/journal.jsonl", "garbage\n" + text).ok());
  ResumeReport report;
  auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(d.status().message().find("line 1"), std::string::npos) << d.status().ToString();
}

// ---- hostile or damaged capture folders -----------------------------------

// A closed capture with verified frames of views 0 and 1, copied to a fresh
// folder per call; its path.
std::string DamageableCapture(const std::string& name) {
  static const std::string original = [] {
    auto d = NewDataset("dataset_hostile_original");
    EXPECT_TRUE(d->StoreFrame(RawFrame(64, 48, 1), {0, 0, "cam", 0, 0, 64, 48}).ok());
    EXPECT_TRUE(d->StoreFrame(RawFrame(64, 48, 2), {1, 1, "cam", 36, 36, 64, 48}).ok());
    return d->dir();
  }();
  const std::string dir = FreshDir(name) + "/c";
  fs::copy(original, dir, fs::copy_options::recursive);
  return dir;
}

void WriteJournal(const std::string& dir, const std::vector<nlohmann::json>& records) {
  std::string text;
  for (const auto& r : records) text += r.dump() + "\n";
  ASSERT_TRUE(WriteFileAtomic(dir + "/journal.jsonl", text).ok());
}

// Index of the first frame_stored record.
size_t FirstFrameRecord(const std::vector<nlohmann::json>& records) {
  size_t i = 0;
  while (i < records.size() && records[i]["event"] != "frame_stored") ++i;
  return i;
}

// Each damaged record gives CorruptData naming the journal line and the field:
// these used to end in std::terminate (missing or mistyped fields) or in a
// "complete" capture with an invalid manifest (no serial) or 39 of 38 views
// (a negative or fractional view).
TEST(CaptureDatasetHostile, DamagedFrameRecordsAreRefusedNamingLineAndField) {
  using Edit = std::function<void(nlohmann::json&)>;
  const std::vector<std::pair<Edit, std::string>> cases = {
      {[](nlohmann::json& r) { r.erase("sha256"); }, "field 'sha256': is missing"},
      {[](nlohmann::json& r) { r["sha256"] = 5; }, "field 'sha256': expected a string, got 5"},
      {[](nlohmann::json& r) { r["sha256"] = "abc"; }, "field 'sha256': expected 64"},
      {[](nlohmann::json& r) { r["view"] = "x"; }, "field 'view': expected an integer"},
      {[](nlohmann::json& r) { r["view"] = -1; },
       "field 'view': expected an integer in [0, 99999], got -1"},
      {[](nlohmann::json& r) { r["view"] = 2.5; },
       "field 'view': expected an integer in [0, 99999], got 2.5"},
      {[](nlohmann::json& r) { r["bytes"] = -1; }, "field 'bytes'"},
      {[](nlohmann::json& r) { r["file"] = 3; }, "field 'file': expected a string"},
      {[](nlohmann::json& r) { r["file"] = "../../outside/victim.png"; }, "field 'file'"},
      {[](nlohmann::json& r) { r.erase("serial"); }, "field 'serial': is missing"},
      {[](nlohmann::json& r) { r["serial"] = ""; }, "field 'serial': is empty"},
      {[](nlohmann::json& r) { r["seq"] = "7"; }, "field 'seq'"},
      {[](nlohmann::json& r) {
         r["serial"] = "CAM-2";
         r["file"] = "frames/000_CAM-2.png";
       },
       "field 'serial': view 0 is planned for camera CAM-1"},
  };
  for (size_t c = 0; c < cases.size(); ++c) {
    const std::string dir = DamageableCapture("dataset_bad_record");
    auto records = ReadJournal(dir);
    const size_t index = FirstFrameRecord(records);
    cases[c].first(records[index]);
    WriteJournal(dir, records);
    ResumeReport report;
    const auto d = CaptureDataset::OpenForResume(dir, {}, &report);
    ASSERT_FALSE(d.ok()) << "case " << c;
    EXPECT_EQ(d.status().code(), StatusCode::kCorruptData) << d.status().ToString();
    const std::string line = dir + "/journal.jsonl: line " + std::to_string(index + 1) + ": ";
    EXPECT_NE(d.status().message().find(line + cases[c].second), std::string::npos)
        << d.status().ToString();
    EXPECT_NE(d.status().message().find("by hand"), std::string::npos) << d.status().ToString();
    EXPECT_TRUE(fs::exists(dir + "/frames/001_CAM-1.png"))
        << "nothing is moved when resume is refused";
  }
}

// A copy of view 0's record relabelled as view 1 used to get view 1's genuine
// frame quarantined and view 0's image accepted for view 1.
TEST(CaptureDatasetHostile, ARecordCopiedOntoAnotherViewIsRefused) {
  const std::string dir = DamageableCapture("dataset_duplicate");
  auto records = ReadJournal(dir);
  nlohmann::json copy = records[FirstFrameRecord(records)];
  copy["view"] = 1;
  copy["seq"] = 1000;
  records.push_back(copy);
  WriteJournal(dir, records);
  ResumeReport report;
  const auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.status().message().find("line " + std::to_string(records.size()) + ": field 'file'"),
            std::string::npos)
      << d.status().ToString();
  EXPECT_TRUE(fs::exists(dir + "/frames/001_CAM-1.png"));
  EXPECT_FALSE(fs::exists(dir + "/quarantine"));
}

// The same with the copied record made consistent (its file name) and the
// frame file copied under that name: the record's own checks pass, the
// duplicate content does not.
TEST(CaptureDatasetHostile, AFrameCopiedWithItsRecordOntoAnotherViewIsRefused) {
  const std::string dir = DamageableCapture("dataset_duplicate_content");
  auto records = ReadJournal(dir);
  const nlohmann::json original = records[FirstFrameRecord(records)];
  nlohmann::json copy = original;
  copy["view"] = 1;
  copy["seq"] = 1000;
  copy["file"] = "frames/001_CAM-1.png";
  fs::copy_file(dir + "/" + original["file"].get<std::string>(), dir + "/frames/001_CAM-1.png",
                fs::copy_options::overwrite_existing);
  records.push_back(copy);
  WriteJournal(dir, records);
  ResumeReport report;
  const auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), StatusCode::kCorruptData) << d.status().ToString();
  EXPECT_NE(
      d.status().message().find("line " + std::to_string(records.size()) +
                                ": field 'sha256': view 1 has the same frame content as view 0"),
      std::string::npos)
      << d.status().ToString();
  EXPECT_FALSE(fs::exists(dir + "/quarantine"));
  const auto verified = VerifiedFrames(dir, records);
  EXPECT_FALSE(verified.ok()) << "replay reads frames through the same check";
}

// Resume writes into journal.jsonl, frames/ and quarantine/: a symlink there
// used to send truncation, re-shot frames or quarantined files outside the capture.
TEST(CaptureDatasetHostile, SymlinksAreRefusedForWriting) {
  for (const std::string entry : {"journal.jsonl", "frames", "quarantine"}) {
    const std::string dir = DamageableCapture("dataset_symlink");
    const std::string outside = fs::path(dir).parent_path().string() + "/outside_" + entry;
    if (entry == "quarantine") {
      fs::create_directory(outside);
    } else {
      fs::rename(dir + "/" + entry, outside);
    }
    fs::create_symlink(outside, dir + "/" + entry);
    std::ofstream(dir + "/journal.jsonl", std::ios::app)
        << "{\"event\":\"cut sh";                                 // would be truncated
    std::ofstream(dir + "/frames/009_CAM-1.png") << "unvouched";  // would be quarantined
    const auto before = ReadFileBytes(dir + "/journal.jsonl");
    ResumeReport report;
    const auto d = CaptureDataset::OpenForResume(dir, {}, &report);
    ASSERT_FALSE(d.ok()) << entry;
    EXPECT_EQ(d.status().code(), StatusCode::kFailedPrecondition) << d.status().ToString();
    EXPECT_NE(d.status().message().find(dir + "/" + entry + " is a symlink"), std::string::npos)
        << d.status().ToString();
    EXPECT_EQ(*ReadFileBytes(dir + "/journal.jsonl"), *before) << entry;
    EXPECT_TRUE(fs::exists(dir + "/frames/009_CAM-1.png")) << entry;
  }
}

// A frame replaced by a symlink to /dev/zero used to hang resume while hashing it.
TEST(CaptureDatasetHostile, AFrameLeadingOutsideIsNotReadAndIsQuarantined) {
  const std::string dir = DamageableCapture("dataset_frame_symlink");
  fs::remove(dir + "/frames/000_CAM-1.png");
  fs::create_symlink("/dev/zero", dir + "/frames/000_CAM-1.png");
  ResumeReport report;
  const auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_TRUE(d.ok()) << d.status().ToString();
  EXPECT_FALSE((*d)->HasVerifiedFrame(0));
  EXPECT_TRUE((*d)->HasVerifiedFrame(1));
  EXPECT_TRUE(fs::is_symlink(dir + "/quarantine/000_CAM-1.png"));
  const auto verified = VerifiedFrames(dir, ReadJournal(dir));
  ASSERT_TRUE(verified.ok());
  EXPECT_EQ(verified->count(0), 0u);
}

// A record vouches for the exact size: a larger `bytes` with the right SHA-256
// is refused as much as a smaller one.
TEST(CaptureDatasetHostile, AFrameMustHaveExactlyTheRecordedSize) {
  const std::string dir = FreshDir("dataset_frame_size");
  const std::string content = "frame bytes";
  std::ofstream(dir + "/f.png", std::ios::binary) << content;
  const std::string sha256 = Sha256Hex(content.data(), content.size());
  EXPECT_TRUE(VerifyFrameFile(dir, "f.png", content.size(), sha256).ok());
  for (const uint64_t bytes : {content.size() + 1, uint64_t{1} << 20, content.size() - 1}) {
    const Status s = VerifyFrameFile(dir, "f.png", bytes, sha256).status();
    EXPECT_EQ(s.code(), StatusCode::kCorruptData) << bytes << ": " << s.ToString();
    EXPECT_NE(s.message().find("f.png"), std::string::npos) << s.ToString();
  }
}

// A missing frames/ and folders where files were expected used to end in an
// uncaught filesystem_error.
TEST(CaptureDatasetHostile, MissingFramesFolderAndForeignFoldersAreHandled) {
  std::string dir = DamageableCapture("dataset_no_frames");
  fs::remove_all(dir + "/frames");
  ResumeReport report;
  auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_TRUE(d.ok()) << d.status().ToString();
  EXPECT_EQ(report.frames_verified, 0);
  EXPECT_TRUE(fs::is_directory(dir + "/frames"));
  d = Result<std::unique_ptr<CaptureDataset>>(Internal("closed"));

  dir = DamageableCapture("dataset_foreign_folders");
  fs::create_directories(dir + "/x.tmp.5");
  std::ofstream(dir + "/x.tmp.5/keep") << "not hairrig's";
  fs::create_directories(dir + "/frames/sub.tmp.3");
  std::ofstream(dir + "/frames/sub.tmp.3/a") << "x";
  d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_TRUE(d.ok()) << d.status().ToString();
  EXPECT_TRUE(fs::exists(dir + "/x.tmp.5/keep"));
  EXPECT_TRUE(fs::exists(dir + "/quarantine/sub.tmp.3/a"));
}

// capture.json as a folder used to end in bad_alloc; a non-string config_dir
// in a type_error.
TEST(CaptureDatasetHostile, DamagedCaptureJsonIsNamed) {
  std::string dir = DamageableCapture("dataset_metadata_folder");
  fs::remove(dir + "/capture.json");
  fs::create_directory(dir + "/capture.json");
  ResumeReport report;
  auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.status().message().find(dir + "/capture.json is a folder"), std::string::npos)
      << d.status().ToString();

  dir = DamageableCapture("dataset_metadata_type");
  ASSERT_TRUE(WriteFileAtomic(dir + "/capture.json",
                              R"({"format": "hairrig-capture", "version": 1, "config_dir": 5})")
                  .ok());
  d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.status().message().find("capture.json: field 'config_dir': expected a string"),
            std::string::npos)
      << d.status().ToString();
}

TEST(CaptureDatasetHostile, AChangedPlanIsRefused) {
  const std::string dir = DamageableCapture("dataset_plan");
  ResumeReport report;
  auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_TRUE(d.ok()) << d.status().ToString();
  std::vector<PlannedViewRecord> moved = TestPlan();
  moved[3].angle_deg = 100;
  Status s = (*d)->JournalPlan(moved);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("view 3 (stop 3 at 108 deg"), std::string::npos) << s.ToString();
  EXPECT_NE(s.message().find("now planned as view 3 (stop 3 at 100 deg"), std::string::npos)
      << s.ToString();
  std::vector<PlannedViewRecord> grown = TestPlan();
  grown.push_back({10, 10, 0, "cam", "CAM-1", {}});
  s = (*d)->JournalPlan(grown);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("view 10 (stop 10 at 0 deg, camera cam CAM-1, lights) was added"),
            std::string::npos)
      << s.ToString();
  EXPECT_TRUE((*d)->JournalPlan(TestPlan()).ok());
}

// Killed between creating the capture and journalling its whole plan: resume completes the plan.
TEST(CaptureDatasetHostile, AnInterruptedStartGetsItsPlanCompleted) {
  const std::string dir = FreshDir("dataset_plan_interrupted") + "/c";
  {
    auto d = CaptureDataset::Create(dir, "name: test\n", {}, {});
    ASSERT_TRUE(d.ok());
    const std::vector<PlannedViewRecord> plan = TestPlan();
    ASSERT_TRUE(
        (*d)->JournalPlan(std::vector<PlannedViewRecord>(plan.begin(), plan.begin() + 4)).ok());
  }
  ResumeReport report;
  auto d = CaptureDataset::OpenForResume(dir, {}, &report);
  ASSERT_TRUE(d.ok()) << d.status().ToString();
  ASSERT_TRUE((*d)->JournalPlan(TestPlan()).ok());
  EXPECT_EQ(CountEvents(ReadJournal(dir), "view_planned"), 10);
  EXPECT_TRUE((*d)->StoreFrame(RawFrame(64, 48), {7, 7, "cam", 0, 0, 64, 48}).ok());
}

// Replay decides with the same VerifiedFrames: a record naming a file outside
// the capture (with that file's true checksum) used to be served.
TEST(CaptureDatasetHostile, ReplayServesOnlyVerifiedFramesInsideTheCapture) {
  const std::string dir = DamageableCapture("dataset_replay_escape");
  const std::string victim = fs::path(dir).parent_path().string() + "/victim.png";
  fs::copy_file(dir + "/frames/000_CAM-1.png", victim);
  auto records = ReadJournal(dir);
  records[FirstFrameRecord(records)]["file"] = "../victim.png";
  WriteJournal(dir, records);
  auto source = OpenReplaySource(dir, {});
  ASSERT_FALSE(source.ok());
  EXPECT_NE(source.status().message().find("field 'file'"), std::string::npos)
      << source.status().ToString();

  const std::string linked = DamageableCapture("dataset_replay_symlink");
  for (const char* frame : {"/frames/000_CAM-1.png", "/frames/001_CAM-1.png"}) {
    fs::copy_file(linked + frame, victim, fs::copy_options::overwrite_existing);
    fs::remove(linked + frame);
    fs::create_symlink(victim, linked + frame);
  }
  source = OpenReplaySource(linked, {});
  EXPECT_EQ(source.status().code(), StatusCode::kNotFound) << source.status().ToString();
}

TEST(CaptureDatasetHostile, ReplayOutputMayNotLieInsideTheRecording) {
  const std::string dir = DamageableCapture("dataset_replay_out");
  EXPECT_EQ(CheckReplayOutDir(dir, dir + "/frames/sub").code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(CheckReplayOutDir(dir, dir).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(CheckReplayOutDir(dir, dir + "/../c/x").code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(CheckReplayOutDir(dir, dir + "-replay").ok());
}

// A dataset on a disk of `quota_bytes` (sim_hw/quota_storage.h).
std::unique_ptr<CaptureDataset> DatasetOnDisk(const std::string& name,
                                              std::shared_ptr<QuotaStorage> disk,
                                              const DatasetOptions& options = {}) {
  auto d =
      CaptureDataset::Create(FreshDir(name) + "/c", "name: test\n", {}, options, std::move(disk));
  EXPECT_TRUE(d.ok()) << d.status().ToString();
  if (!d.ok()) return nullptr;
  EXPECT_TRUE((*d)->JournalPlan(TestPlan()).ok());
  return std::move(d).value();
}

// A journal record that no longer fits leaves no part of itself behind: the
// journal stays whole and the capture resumes without a repair.
TEST(CaptureDatasetFullDisk, ARecordThatDoesNotFitLeavesTheJournalWhole) {
  auto disk = std::make_shared<QuotaStorage>(QuotaStorageOptions{.quota_bytes = 1'000'000});
  auto d = DatasetOnDisk("dataset_full_journal", disk);
  ASSERT_TRUE(d);
  ASSERT_TRUE(d->StoreFrame(RawFrame(64, 48), {0, 0, "cam", 0, 0, 64, 48}).ok());
  disk->Consume(1'000'000 - disk->used_bytes() - 20);  // 20 bytes left: half a record fits
  const Status full =
      d->Append({{"event", "fault"}, {"what", "a record longer than twenty bytes"}});
  EXPECT_EQ(full.code(), StatusCode::kIoError);
  EXPECT_NE(full.message().find("No space left on device"), std::string::npos) << full.message();
  const std::string dir = d->dir();
  d.reset();
  size_t cut_short = 0;
  ASSERT_TRUE(ReadJournalRecords(dir + "/journal.jsonl", &cut_short).ok());
  EXPECT_EQ(cut_short, 0u) << "part of the record stayed in the journal";
  ResumeReport report;
  ASSERT_TRUE(CaptureDataset::OpenForResume(dir, {}, &report).ok());
  EXPECT_EQ(report.journal_bytes_dropped, 0u);
  EXPECT_EQ(report.frames_verified, 1);
}

// A full disk while the capture is created (its rig.yaml cannot be written)
// leaves no folder behind, so that the same --out can be given again.
TEST(CaptureDatasetFullDisk, ACaptureThatCannotBeCreatedLeavesNoFolder) {
  const std::string dir = FreshDir("dataset_full_create") + "/c";
  auto disk = std::make_shared<QuotaStorage>(QuotaStorageOptions{.quota_bytes = 4});
  const auto d = CaptureDataset::Create(dir, "name: test\n", {}, {}, disk);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), StatusCode::kIoError);
  EXPECT_NE(d.status().message().find("No space left on device"), std::string::npos)
      << d.status().ToString();
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_TRUE(CaptureDataset::Create(dir, "name: test\n", {}, {}).ok());
}

// The file system, where another hairrig process (a --resume of the same
// folder) opens and locks the journal of a capture being created as soon as
// its capture.json is written.
class AnotherProcessTakesTheJournal : public PosixCaptureStorage {
 public:
  ~AnotherProcessTakesTheJournal() override {
    if (fd_ >= 0) ::close(fd_);
  }
  Status WriteFileAtomic(const std::string& path, const void* data, size_t size,
                         const StageHook& on_stage) override {
    HR_RETURN_IF_ERROR(PosixCaptureStorage::WriteFileAtomic(path, data, size, on_stage));
    if (fs::path(path).filename() != "capture.json") return Status::Ok();
    const std::string journal = (fs::path(path).parent_path() / "journal.jsonl").string();
    fd_ = ::open(journal.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    EXPECT_GE(fd_, 0);
    EXPECT_EQ(::flock(fd_, LOCK_EX | LOCK_NB), 0);
    return Status::Ok();
  }

 private:
  int fd_ = -1;
};

// Create removes what it made when it fails, but not a folder another
// process has taken over: with the journal's lock held by that process, the
// folder is its capture.
TEST(CaptureDataset, CreateKeepsAFolderAnotherProcessTookOver) {
  const std::string dir = FreshDir("dataset_create_locked") + "/c";
  const auto d = CaptureDataset::Create(dir, "name: test\n", {}, {},
                                        std::make_shared<AnotherProcessTakesTheJournal>());
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), StatusCode::kFailedPrecondition) << d.status().ToString();
  EXPECT_NE(d.status().message().find("another hairrig process"), std::string::npos)
      << d.status().ToString();
  for (const char* file : {"rig.yaml", "capture.json", "journal.jsonl", "frames"})
    EXPECT_TRUE(fs::exists(fs::path(dir) / file)) << file;
}

// storage.min_free_mb holds for each frame: one that would leave less free
// is refused before a byte of it is written.
TEST(CaptureDatasetFullDisk, AFrameThatWouldLeaveLessThanTheMinimumIsNotWritten) {
  // 100 bytes above the limit: creating the capture takes more.
  auto disk = std::make_shared<QuotaStorage>(QuotaStorageOptions{.quota_bytes = 1'000'100});
  auto d = DatasetOnDisk("dataset_min_free", disk, {.min_free_bytes = 1'000'000});
  ASSERT_TRUE(d);
  const auto refused = d->StoreFrame(RawFrame(64, 48), {0, 0, "cam", 0, 0, 64, 48});
  EXPECT_EQ(refused.status().code(), StatusCode::kIoError);
  EXPECT_NE(refused.status().message().find(d->dir() + ": "), std::string::npos)
      << refused.status().ToString();
  EXPECT_NE(refused.status().message().find("MB free"), std::string::npos)
      << refused.status().ToString();
  EXPECT_NE(refused.status().message().find("1.000 MB storage.min_free_mb"), std::string::npos)
      << refused.status().ToString();
  EXPECT_TRUE(fs::is_empty(d->dir() + "/frames"));
  EXPECT_EQ(CountEvents(ReadJournal(d->dir()), "frame_stored"), 0);
}

}  // namespace
}  // namespace hairrig
