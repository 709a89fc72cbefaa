#include "rig/capture_dataset.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "core/file_util.h"
#include "rig/capture_test_util.h"

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

std::unique_ptr<CaptureDataset> NewDataset(const std::string& name) {
  const std::string dir = FreshDir(name) + "/c";
  auto d = CaptureDataset::Create(dir, "name: test\n", {{"config_dir", "/"}}, {});
  EXPECT_TRUE(d.ok()) << d.status().ToString();
  return d.ok() ? std::move(d).value() : nullptr;
}

TEST(CaptureDataset, StoresAVerifiedFrameAndRefusesToOverwriteIt) {
  auto d = NewDataset("dataset_store");
  ASSERT_TRUE(d);
  auto stored = d->StoreFrame(RawFrame(64, 48), {3, 1, "cam", 10, 10.001, 64, 48});
  ASSERT_TRUE(stored.ok()) << stored.status().ToString();
  EXPECT_EQ(stored->record["file"], "frames/003_CAM-1.png");
  EXPECT_TRUE(d->HasVerifiedFrame(3));
  const auto again = d->StoreFrame(RawFrame(64, 48, 7), {3, 1, "cam", 10, 10, 64, 48});
  EXPECT_EQ(again.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(VerifiedFramesOnDisk(d->dir()).at(3)["sha256"], stored->record["sha256"]);
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
  EXPECT_NE(r.status().message().find("does not decode"), std::string::npos) << r.status().ToString();
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
    sha_kept = d->StoreFrame(RawFrame(64, 48, 1), {0, 0, "cam", 0, 0, 64, 48})->record["sha256"];
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

}  // namespace
}  // namespace hairrig
