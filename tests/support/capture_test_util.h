// Helpers shared by the capture tests: a fresh folder, a variant of the small
// test rig (tests/data/small_rig.yaml) with extra YAML, and dataset checks that
// re-derive everything from the files on disk.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hairrig::testing {

// A new empty folder under the test temp dir; its path.
std::string FreshDir(const std::string& name);
// Writes the small test rig into `dir` with top-level sections replaced or
// added: {{"retries", "retries:\n  frame_timeout_s: 1\n"}}. Returns its path.
std::string WriteSmallRig(const std::string& dir,
                          const std::map<std::string, std::string>& sections = {});
// The small rig's `devices:` section with these turntable and camera entries
// (YAML flow maps such as "{name: upper, backend: sim, serial: SIM-CAM-UPPER,
// trigger_line: trig0}"); the lights, trigger line and e-stop as in the file.
std::string SmallRigDevices(const std::string& turntable, const std::string& upper_camera,
                            const std::string& lower_camera);
std::vector<nlohmann::json> ReadJournal(const std::string& capture_dir);
// view -> frame_stored record, for records whose file verifies (size and SHA-256
// recomputed here with sha256sum, an independent implementation).
std::map<int, nlohmann::json> VerifiedFramesOnDisk(const std::string& capture_dir);
int CountEvents(const std::vector<nlohmann::json>& journal, const std::string& event);

}  // namespace hairrig::testing
