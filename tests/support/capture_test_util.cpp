#include "tests/support/capture_test_util.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/file_util.h"

namespace hairrig::testing {

namespace fs = std::filesystem;

std::string FreshDir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("hairrig_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string WriteSmallRig(const std::string& dir,
                          const std::map<std::string, std::string>& sections) {
  const fs::path source = fs::absolute("tests/data/small_rig.yaml");
  std::ifstream in(source);
  std::string text, line;
  std::map<std::string, std::string> pending = sections;
  bool skipping = false;
  while (std::getline(in, line)) {
    const bool top_level = !line.empty() && line[0] != ' ' && line[0] != '#';
    if (top_level) {
      const std::string key = line.substr(0, line.find(':'));
      skipping = pending.count(key) > 0;
      if (skipping) {
        text += pending[key];
        pending.erase(key);
        continue;
      }
    }
    if (skipping && !line.empty() && line[0] == ' ') continue;
    skipping = false;
    text += line + "\n";
  }
  for (const auto& [key, section] : pending) text += section;
  const std::string scene = (source.parent_path() / "small_scene.yaml").string();
  // The scene path must resolve from the test's folder.
  const size_t at = text.find("scene: small_scene.yaml");
  if (at != std::string::npos)
    text.replace(at, std::string("scene: small_scene.yaml").size(), "scene: " + scene);
  const std::string path = dir + "/rig.yaml";
  EXPECT_TRUE(WriteFileAtomic(path, text).ok());
  return path;
}

std::string SmallRigDevices(const std::string& turntable, const std::string& upper_camera,
                            const std::string& lower_camera) {
  return "devices:\n"
         "  turntable: " +
         turntable +
         "\n"
         "  lights:\n"
         "    - {name: top, backend: sim, serial: SIM-LED-TOP, light: top}\n"
         "    - {name: bottom, backend: sim, serial: SIM-LED-BOTTOM, light: bottom}\n"
         "  trigger_lines:\n"
         "    - {name: trig0, backend: sim, serial: SIM-GPIO-0}\n"
         "  cameras:\n"
         "    - " +
         upper_camera +
         "\n"
         "    - " +
         lower_camera +
         "\n"
         "  input_lines:\n"
         "    - {name: estop, backend: sim, serial: SIM-ESTOP}\n";
}

std::vector<nlohmann::json> ReadJournal(const std::string& capture_dir) {
  std::vector<nlohmann::json> records;
  std::ifstream in(capture_dir + "/journal.jsonl");
  std::string line;
  while (std::getline(in, line)) {
    // A record cut short by a kill is not a record (resume drops it too).
    auto record = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (!record.is_discarded()) records.push_back(std::move(record));
  }
  return records;
}

namespace {
std::string Sha256sum(const std::string& path) {
  std::FILE* pipe = ::popen(("sha256sum '" + path + "' 2>/dev/null").c_str(), "r");
  if (!pipe) return "";
  char out[65] = {};
  const size_t n = std::fread(out, 1, 64, pipe);
  ::pclose(pipe);
  return n == 64 ? std::string(out) : "";
}
}  // namespace

std::map<int, nlohmann::json> VerifiedFramesOnDisk(const std::string& capture_dir) {
  std::map<int, nlohmann::json> verified;
  for (const auto& r : ReadJournal(capture_dir)) {
    if (r.value("event", "") != "frame_stored") continue;
    const std::string path = capture_dir + "/" + r["file"].get<std::string>();
    std::error_code ec;
    if (fs::file_size(path, ec) == r["bytes"].get<uint64_t>() && !ec &&
        Sha256sum(path) == r["sha256"]) {
      verified[r["view"].get<int>()] = r;
    }
  }
  return verified;
}

int CountEvents(const std::vector<nlohmann::json>& journal, const std::string& event) {
  int n = 0;
  for (const auto& r : journal) n += r.value("event", "") == event ? 1 : 0;
  return n;
}

}  // namespace hairrig::testing
