// The command line on hostile or damaged input, as a careless user or an
// attacker hands it in: every case ends with exit code 1 and a message naming
// the file and the field ("hairrig: error: ..."), never a crash (exit 134), a
// hang, a write outside the capture folder or a success on a damaged dataset.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "tests/support/command_run.h"

namespace {

namespace fs = std::filesystem;
using hairrig_test::CommandRun;
using hairrig_test::Hairrig;

// Every command runs under `timeout`: a hang fails the test (exit 124) instead of blocking ctest.
CommandRun Hostile(const std::string& args) {
  return Hairrig("--log-level error " + args, "timeout -k 5 60 ");
}

void ExpectCleanError(const CommandRun& r, const std::string& expected) {
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("hairrig: error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("terminate called"), std::string::npos) << r.output;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

class CliHostile : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = ::testing::TempDir() + "/hairrig_cli_hostile";
    fs::remove_all(root_);
    fs::create_directories(root_);
    const CommandRun r =
        Hostile("capture --config tests/data/small_rig.yaml --out " + root_ + "/recorded");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  // A fresh copy of the recorded capture.
  static std::string Copy(const std::string& name) {
    const std::string dir = root_ + "/" + name;
    fs::remove_all(dir);
    fs::copy(root_ + "/recorded", dir, fs::copy_options::recursive);
    return dir;
  }
  // Applies `edit` to the capture's first frame_stored record.
  static void EditFirstFrameRecord(const std::string& dir,
                                   const std::function<void(nlohmann::json&)>& edit) {
    std::ifstream in(dir + "/journal.jsonl");
    std::string line, text;
    bool done = false;
    while (std::getline(in, line)) {
      nlohmann::json r = nlohmann::json::parse(line);
      if (!done && r["event"] == "frame_stored") {
        edit(r);
        done = true;
      }
      text += r.dump() + "\n";
    }
    std::ofstream(dir + "/journal.jsonl", std::ios::trunc) << text;
  }
  static std::string root_;
};
std::string CliHostile::root_;

TEST_F(CliHostile, DamagedFrameRecordsStopResumeWithLineAndField) {
  const std::vector<std::pair<std::function<void(nlohmann::json&)>, std::string>> cases = {
      {[](nlohmann::json& r) { r.erase("sha256"); }, "field 'sha256': is missing"},
      {[](nlohmann::json& r) { r["file"] = 7; }, "field 'file'"},
      {[](nlohmann::json& r) { r.erase("serial"); }, "field 'serial': is missing"},
      {[](nlohmann::json& r) { r["view"] = -1; }, "field 'view'"},
      {[](nlohmann::json& r) { r["view"] = 2.5; }, "field 'view'"},
      {[](nlohmann::json& r) { r["seq"] = "x"; }, "field 'seq'"},
  };
  for (const auto& [edit, expected] : cases) {
    const std::string dir = Copy("bad_record");
    EditFirstFrameRecord(dir, edit);
    const std::string manifest = ReadText(dir + "/manifest.json");
    ExpectCleanError(Hostile("capture --resume --out " + dir), "journal.jsonl: line ");
    ExpectCleanError(Hostile("replay " + dir + " --out " + dir + "-replay"), expected);
    EXPECT_EQ(ReadText(dir + "/manifest.json"), manifest)
        << "a refused resume leaves the manifest alone";
    EXPECT_FALSE(nlohmann::json::parse(manifest, nullptr, false).is_discarded());
  }
}

TEST_F(CliHostile, DamagedCaptureJsonIsNamed) {
  std::string dir = Copy("capture_json_folder");
  fs::remove(dir + "/capture.json");
  fs::create_directory(dir + "/capture.json");
  ExpectCleanError(Hostile("capture --resume --out " + dir), "capture.json is a folder");
  dir = Copy("capture_json_type");
  std::ofstream(dir + "/capture.json", std::ios::trunc)
      << R"({"format": "hairrig-capture", "version": 1, "config_dir": 5})";
  ExpectCleanError(Hostile("capture --resume --out " + dir), "field 'config_dir'");
}

TEST_F(CliHostile, ResumeFollowsNoSymlinkOutOfTheCapture) {
  const std::string dir = Copy("journal_symlink");
  const std::string outside = root_ + "/outside_journal.jsonl";
  fs::rename(dir + "/journal.jsonl", outside);
  fs::create_symlink(outside, dir + "/journal.jsonl");
  const std::string before = ReadText(outside);
  ExpectCleanError(Hostile("capture --resume --out " + dir), "journal.jsonl is a symlink");
  EXPECT_EQ(ReadText(outside), before);

  const std::string frames = Copy("frame_to_dev_zero");
  fs::remove(frames + "/frames/000_SIM-CAM-UPPER.png");
  fs::create_symlink("/dev/zero", frames + "/frames/000_SIM-CAM-UPPER.png");
  const CommandRun replay = Hostile("replay " + frames + " --out " + frames + "-replay --json");
  EXPECT_EQ(replay.exit_code, 3) << replay.output;  // incomplete: view 0 is not served
  EXPECT_NE(replay.output.find("\"missing_views\":[0]"), std::string::npos) << replay.output;
}

TEST_F(CliHostile, ReplayStaysInsideTheRecording) {
  const std::string dir = Copy("replay_escape");
  fs::copy_file(dir + "/frames/001_SIM-CAM-LOWER.png", root_ + "/victim.png",
                fs::copy_options::overwrite_existing);
  EditFirstFrameRecord(dir, [](nlohmann::json& r) { r["file"] = "../victim.png"; });
  ExpectCleanError(Hostile("replay " + dir + " --out " + root_ + "/escape_out"), "field 'file'");
  EXPECT_FALSE(fs::exists(root_ + "/escape_out"));
  ExpectCleanError(Hostile("replay " + root_ + "/recorded --out " + root_ + "/recorded/frames/x"),
                   "lies inside the recording");
  EXPECT_FALSE(fs::exists(root_ + "/recorded/frames/x"));
}

TEST_F(CliHostile, OnlyRegularFilesAreRead) {
  const std::string fifo = root_ + "/config.fifo";
  fs::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  ExpectCleanError(Hostile("devices --config " + fifo), "is a FIFO");
  ExpectCleanError(Hostile("devices --config /dev/zero"), "is a character device");
  ExpectCleanError(Hostile("devices --config " + root_), "is a folder");
}

TEST_F(CliHostile, HostileStrandFilesAndModelsAreRefused) {
  // A bare .hair header claiming 2^32-1 strands (it used to allocate 16 GB).
  std::vector<char> header(128, 0);
  std::memcpy(header.data(), "HAIR", 4);
  const uint32_t huge = 0xffffffffu, points_only = 2;
  std::memcpy(header.data() + 4, &huge, 4);
  std::memcpy(header.data() + 8, &huge, 4);
  std::memcpy(header.data() + 12, &points_only, 4);
  std::ofstream(root_ + "/huge.hair", std::ios::binary).write(header.data(), 128);
  ExpectCleanError(Hostile("fit " + root_ + "/huge.hair --out " + root_ + "/m.json"),
                   "header claims 4294967295 strands");
  // A PLY element of 9e18 empty records (it used to loop for ever).
  std::ofstream(root_ + "/junk.ply")
      << "ply\nformat ascii 1.0\nelement junk 9000000000000000000\nelement vertex 1\n"
         "property float x\nproperty float y\nproperty float z\nelement strand 1\n"
         "property int nsegs\nend_header\n0 0 0\n0\n";
  ExpectCleanError(Hostile("fit " + root_ + "/junk.ply --out " + root_ + "/m.json"),
                   "element 'junk'");
  // A helix model whose cluster_of_strand is a string (it used to end in std::terminate).
  std::ofstream(root_ + "/model.json")
      << R"({"format": "hairrig-helix-model", "version": 1, "guides": [{"strand": 0, "elements": [{"start_mm": [0, 0, 0],
            "start_tangent": [1, 0, 0], "darboux_per_mm": [0, 0, 0], "length_mm": 1}]}], "cluster_of_strand": "abc"})";
  ExpectCleanError(Hostile("simulate " + root_ + "/model.json --out " + root_ + "/sim"),
                   "field 'cluster_of_strand'");
}

// A FIFO under the journal's name used to block `capture --resume` for ever
// (opening it for appending waited for a reader); replay refused it already.
TEST_F(CliHostile, ResumeRefusesAJournalThatIsNotARegularFile) {
  const std::string dir = Copy("journal_fifo");
  fs::remove(dir + "/journal.jsonl");
  ASSERT_EQ(::mkfifo((dir + "/journal.jsonl").c_str(), 0600), 0);
  ExpectCleanError(Hostile("capture --resume --out " + dir), "journal.jsonl is a FIFO");
  ExpectCleanError(Hostile("replay " + dir + " --out " + dir + "-replay"),
                   "journal.jsonl is a FIFO");
}

// A frame record vouches for the frame's exact size: one claiming more bytes
// than the file holds (with the file's SHA-256) does not verify.
TEST_F(CliHostile, AFrameLargerOnRecordThanOnDiskIsNotTrusted) {
  const std::string dir = Copy("frame_bytes_larger");
  std::string file;
  int view = -1;
  EditFirstFrameRecord(dir, [&file, &view](nlohmann::json& r) {
    r["bytes"] = r["bytes"].get<uint64_t>() + 1;
    file = r["file"].get<std::string>();
    view = r["view"].get<int>();
  });
  const CommandRun replay = Hostile("replay " + dir + " --out " + dir + "-replay --json");
  EXPECT_EQ(replay.exit_code, 3) << replay.output;  // incomplete: that view is not served
  EXPECT_NE(replay.output.find("\"missing_views\":[" + std::to_string(view) + "]"),
            std::string::npos)
      << replay.output;
  const CommandRun resume = Hostile("capture --resume --out " + dir);
  EXPECT_EQ(resume.exit_code, 0) << resume.output;  // the frame is shot again
  EXPECT_TRUE(fs::exists(dir + "/quarantine/" + fs::path(file).filename().string())) << file;
}

// The small test rig named `rig_name` on the scene file `scene`, written as `file`.
std::string SmallRigVariant(const std::string& file, const std::string& rig_name,
                            const std::string& scene) {
  std::string text = ReadText("tests/data/small_rig.yaml");
  const auto replace = [&text](const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
  };
  replace("name: small simulated rig", "name: " + rig_name);
  replace("scene: small_scene.yaml", "scene: " + scene);
  const std::string path = ::testing::TempDir() + "/hairrig_cli_hostile_" + file;
  std::ofstream(path, std::ios::trunc) << text;
  return path;
}

// Config text is written to JSON (capture.json): text that is not UTF-8 used
// to end in "internal error" from the JSON writer; it is refused on reading.
TEST_F(CliHostile, ConfigTextThatIsNotUtf8IsRefusedNamingTheField) {
  const std::string config = SmallRigVariant("latin1.yaml", "caf\xE9 rig",
                                             fs::absolute("tests/data/small_scene.yaml").string());
  const CommandRun r =
      Hostile("capture --config " + config + " --out " + root_ + "/latin1_capture");
  ExpectCleanError(r, config + ":3:7: field 'name': text that is not valid UTF-8");
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
}

// A file that is not a config, named where one is expected, is refused without
// its content appearing in the message.
TEST_F(CliHostile, AForeignFileNamedAsASceneIsNotQuoted) {
  const std::string foreign = root_ + "/passwd";
  std::ofstream(foreign)
      << "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n";
  const std::string config = SmallRigVariant("foreign_scene.yaml", "small simulated rig", foreign);
  const CommandRun r =
      Hostile("capture --config " + config + " --out " + root_ + "/foreign_capture");
  ExpectCleanError(r, foreign + ": expected a YAML map at the top level, got text of 79 bytes");
  EXPECT_EQ(r.output.find("root:x"), std::string::npos) << r.output;
}

// Argument errors, CLI11's existence checks included, end as every other error.
TEST_F(CliHostile, ArgumentErrorsExitOneWithTheErrorForm) {
  ExpectCleanError(
      Hostile("calibrate " + root_ + "/recorded --intrinsics " + root_ + "/absent.json"),
      "File does not exist");
  ExpectCleanError(Hostile("calibrate " + root_ + "/recorded --intrinsics " + root_), root_);
  ExpectCleanError(Hostile("simulate " + root_ + "/absent_model.json --out " + root_ + "/sim"),
                   "absent_model.json");
  ExpectCleanError(Hostile("devices --no-such-option"), "--no-such-option");
  EXPECT_EQ(Hostile("--help").exit_code, 0);
}

// A USC-HairSalon .data file of the given strands.
void WriteData(const std::string& path,
               const std::vector<std::vector<std::array<float, 3>>>& strands) {
  std::ofstream out(path, std::ios::binary);
  const auto put = [&](const auto& value) {
    out.write(reinterpret_cast<const char*>(&value), sizeof value);
  };
  put(static_cast<int32_t>(strands.size()));
  for (const auto& strand : strands) {
    put(static_cast<int32_t>(strand.size()));
    for (const auto& p : strand) put(p);
  }
}

// Strand-level errors name the file, the strand (0-based, in the file's
// order) and, for a coordinate, the vertex: near float's largest (3.4e38)
// differences overflow, which once reached the fit as "strand -1".
TEST_F(CliHostile, StrandErrorsNameTheFileAndTheStrand) {
  const std::vector<std::array<float, 3>> straight = {
      {0, 0, 0}, {0, 0, -10}, {0, 0, -20}, {0, 0, -30}};
  const std::string huge = root_ + "/huge_coordinate.data";
  WriteData(huge, {straight, straight, {{0, 0, 0}, {0, 0, -10}, {3.4e38f, 0, -20}}});
  CommandRun r = Hostile("fit " + huge + " --out " + root_ + "/m.json");
  ExpectCleanError(r, huge + ": strand 2 vertex 2 (point 10): x = 3.4e+38 mm");
  EXPECT_EQ(r.output.find("strand -1"), std::string::npos) << r.output;

  const std::string flat = root_ + "/zero_length.data";
  WriteData(flat, {straight, {{5, 5, 0}, {5, 5, 0}}, straight});
  ExpectCleanError(Hostile("fit " + flat + " --guides 3 --out " + root_ + "/m.json"),
                   flat + ": strand 1: fewer than 2 distinct points");
}

}  // namespace
