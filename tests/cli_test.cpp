// The hairrig command line as a user meets it: clear errors with non-zero exit
// codes on bad input, JSON summaries with --json, files where it says.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "tests/support/command_run.h"
#include "tests/support/gvcp_packets.h"

namespace {

using hairrig_test::CommandRun;
using hairrig_test::Hairrig;
using hairrig_test::LastLineJson;

std::string TempFile(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(Cli, HelpListsTheCommands) {
  const CommandRun r = Hairrig("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("devices"), std::string::npos);
  EXPECT_NE(r.output.find("sim"), std::string::npos);
  EXPECT_NE(r.output.find("capture"), std::string::npos);
  EXPECT_NE(r.output.find("replay"), std::string::npos);
}

// The options every command shares are checked before any command runs, and
// the error names the option.
TEST(Cli, ABadLogLevelIsNamed) {
  const CommandRun r = Hairrig("--log-level loud devices");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--log-level 'loud'"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("healthy"), std::string::npos) << "no command ran";
}

TEST(Cli, DevicesOnTheDefaultRigAreHealthyAsJson) {
  const CommandRun r = Hairrig("devices --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["total"], 7);
  EXPECT_EQ(j["healthy"], 7);
}

// A rig whose top panel sits on a GPIO chip this machine does not have: the
// table names it with why, and the command exits 3 (the rig is not ready).
TEST(Cli, DevicesExitsThreeWhenADeviceIsUnhealthy) {
  std::string text = ReadText("etc/sim-rig.yaml");
  const std::string etc = std::filesystem::absolute("etc").string();
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"scene: scenes/", "scene: " + etc + "/scenes/"},
           {"box: calib-box.yaml", "box: " + etc + "/calib-box.yaml"},
           {"head: heads/", "head: " + etc + "/heads/"},
           {"{name: top, backend: sim, serial: SIM-LED-TOP, light: top}",
            "{name: top, backend: gpiod, serial: PANEL-TOP-01, chip: no-such-chip, line: 3}"}}) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const CommandRun r = Hairrig("devices --json --config " + TempFile("gpio_rig.yaml", text));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  const auto j = LastLineJson(r.output);
  EXPECT_EQ(j["total"], 7);
  EXPECT_EQ(j["healthy"], 6);
  bool named = false;
  for (const auto& d : j["devices"])
    named |= d["name"] == "top" &&
             d["health"].get<std::string>().find("no-such-chip") != std::string::npos;
  EXPECT_TRUE(named) << r.output;
}

// What is found depends on the machine (none on CI); either way the command
// succeeds, and an empty search says so plainly.
TEST(Cli, DiscoverListsRealDevicesOrSaysThereAreNone) {
  // In a sanitizer build: libgphoto2 2.5.30's USB port driver leaks a 0-byte
  // allocation per camera model it searches for when no USB device exists,
  // from a module it has unloaded by exit, so no LSan suppression can name
  // it (tests/lsan.supp). Leak checking is off for this one command.
  const CommandRun r = Hairrig("devices --discover --json", "ASAN_OPTIONS=detect_leaks=0 ");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = LastLineJson(r.output);
  EXPECT_EQ(j["found"].get<size_t>(), j["devices"].size());
  for (const auto& d : j["devices"])
    EXPECT_NE(d["snippet"].get<std::string>().find("backend: "), std::string::npos);
  if (j["found"] == 0) {
    EXPECT_NE(j["text"].get<std::string>().find("No devices found"), std::string::npos) << r.output;
  }
  EXPECT_NE(Hairrig("devices --discover --config etc/sim-rig.yaml").exit_code, 0);
}

TEST(Cli, BrokenYamlNamesTheFileAndLine) {
  const std::string path = TempFile("broken.yaml", "name: x\ndevices: [1, 2\n");
  const CommandRun r = Hairrig("devices --config " + path);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find(path + ":"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not valid YAML"), std::string::npos) << r.output;
}

TEST(Cli, UnknownBackendNamesTheFieldAndTheChoices) {
  const std::string path = TempFile(
      "rig.yaml", "name: x\ndevices:\n  cameras:\n    - {name: c, backend: ximea, serial: X1}\n");
  const CommandRun r = Hairrig("devices --config " + path);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("devices.cameras[0].backend"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("unknown camera backend 'ximea'"), std::string::npos) << r.output;
}

TEST(Cli, SceneWithTheBoxBehindACameraIsRefused) {
  std::string scene = ReadText("etc/scenes/default.yaml");
  const std::string box = std::filesystem::absolute("etc/calib-box.yaml").string();
  scene.replace(scene.find("../calib-box.yaml"), std::string("../calib-box.yaml").size(), box);
  // Turn the upper camera round: it looks away from the box.
  scene.replace(scene.find("target_mm: [0, 0, 390]"), std::string("target_mm: [0, 0, 390]").size(),
                "target_mm: [1800, 0, 700]");
  const CommandRun r = Hairrig("sim render --view 0 --out " + ::testing::TempDir() +
                               "/x.png --scene " + TempFile("behind.yaml", scene));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("has the calibration box behind it"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("SIM-CAM-UPPER"), std::string::npos) << r.output;
}

TEST(Cli, RenderOneViewWritesTheImage) {
  const std::string out = ::testing::TempDir() + "/view3.png";
  std::filesystem::remove(out);
  const CommandRun r = Hairrig("sim render --view 3 --out " + out + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["camera_serial"], "SIM-CAM-LOWER");
  EXPECT_GT(std::filesystem::file_size(out), 100000u);
  EXPECT_GE(j["tags_unoccluded"].get<int>(), 4);
}

TEST(Cli, RenderCropIsThoseFullResolutionPixels) {
  const std::string full = ::testing::TempDir() + "/view8_full.png",
                    crop = ::testing::TempDir() + "/view8_crop.png";
  ASSERT_EQ(Hairrig("sim render --view 8 --no-noise --out " + full).exit_code, 0);
  const CommandRun r = Hairrig("sim render --view 8 --no-noise --crop 340,680,56,60 --out " + crop);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat whole = cv::imread(full), part = cv::imread(crop);
  ASSERT_EQ(part.cols, 56);
  ASSERT_EQ(part.rows, 60);
  EXPECT_EQ(cv::norm(part, whole(cv::Rect(340, 680, 56, 60)), cv::NORM_INF), 0);
  const CommandRun outside = Hairrig("sim render --view 8 --crop 1190,10,20,20 --out " + crop);
  EXPECT_NE(outside.exit_code, 0);
  EXPECT_NE(outside.output.find("--crop"), std::string::npos) << outside.output;
}

TEST(Cli, BadArgumentsAreRefused) {
  EXPECT_NE(Hairrig("sim render --view 99 --out /tmp/x.png").exit_code, 0);
  EXPECT_NE(Hairrig("sim render --out /tmp/x.png").exit_code, 0);
  EXPECT_NE(Hairrig("sim render --view 1 --out /tmp/x.txt").exit_code, 0);
  EXPECT_NE(Hairrig("frobnicate").exit_code, 0);
}

// A running `hairrig sim serve --no-rtu`, its stdout in `log`. A test that
// ends before stopping it (a failed assertion) kills it, so that no server
// outlives its test and holds the test's output open.
struct SimServe {
  pid_t pid = -1;
  std::string log;
  std::string modbus_port;  // empty when no endpoint was printed

  SimServe() = default;
  SimServe(const SimServe&) = delete;
  SimServe& operator=(const SimServe&) = delete;
  ~SimServe() {
    if (pid <= 0) return;
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
};

// Waits up to 2 minutes for the endpoint (the sanitizer build starts slowly).
void StartSimServe(const std::string& name, SimServe* out) {
  SimServe& serve = *out;
  serve.log = ::testing::TempDir() + "/" + name + ".out";
  std::filesystem::remove(serve.log);
  serve.pid = fork();
  if (serve.pid == 0) {
    std::freopen(serve.log.c_str(), "w", stdout);
    execl(HAIRRIG_BIN, HAIRRIG_BIN, "sim", "serve", "--no-rtu", "--time-scale", "0.01",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  for (int i = 0; i < 2400 && serve.pid > 0 && serve.modbus_port.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const std::string text = ReadText(serve.log);
    const size_t at = text.find("127.0.0.1:");
    const size_t end = text.find(' ', at);
    if (at != std::string::npos && end != std::string::npos)
      serve.modbus_port = text.substr(at + 10, end - at - 10);
  }
}

// Stops it with SIGINT; its exit code, -1 when it did not exit by itself.
int StopSimServe(SimServe* serve) {
  kill(serve->pid, SIGINT);
  int status = 0;
  const pid_t reaped = waitpid(serve->pid, &status, 0);
  if (reaped == serve->pid) serve->pid = -1;
  if (reaped <= 0 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

// `hairrig sim serve` runs the simulated Modbus controller for outside tools
// until Ctrl-C, and says how to reach it.
// Serves the Modbus controller, the DSLRs and the GigE Vision camera; outside
// tools (mbpoll, Aravis' arv-camera-test) reach them until Ctrl-C.
TEST(Cli, SimServeAnswersOutsideToolsUntilCtrlC) {
  SimServe serve;
  StartSimServe("sim_serve", &serve);
  ASSERT_GT(serve.pid, 0);
  const std::string& port = serve.modbus_port;
  ASSERT_FALSE(port.empty()) << "no endpoint printed:\n" << ReadText(serve.log);
  const std::string mbpoll =
      "mbpoll -m tcp -p " + port + " -a 1 -0 -1 -t 4:hex -r 100 -c 2 127.0.0.1 > /dev/null";
  EXPECT_EQ(std::system(mbpoll.c_str()), 0) << mbpoll;
  // Aravis' own test client streams from the GigE fake for 4 s (then SIGINT, which it handles).
  const std::string arv_log = ::testing::TempDir() + "/arv_camera_test.out";
  const std::string arv =
      "timeout -s INT 4 arv-camera-test-0.8 -n 127.0.0.1 > " + arv_log + " 2>&1";
  std::system(arv.c_str());
  const std::string arv_text = ReadText(arv_log);
  EXPECT_NE(arv_text.find("device serial number   = SIM-CAM-LOWER"), std::string::npos) << arv_text;
  EXPECT_NE(arv_text.find("image width            = 1200"), std::string::npos) << arv_text;
  EXPECT_NE(arv_text.find("n_completed_buffers"), std::string::npos) << arv_text;
  EXPECT_EQ(StopSimServe(&serve), 0);
  const std::string text = ReadText(serve.log);
  EXPECT_NE(text.find("try: mbpoll -m tcp -p " + port), std::string::npos) << text;
  EXPECT_NE(text.find("stopped (SIGINT)"), std::string::npos) << text;
  EXPECT_NE(text.find(": 1 requests served"), std::string::npos) << text;
  EXPECT_NE(text.find("try: gphoto2 --camera 'Hairrig Simulated DSLR' --port disk:"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("export CAMLIBS="), std::string::npos) << text;
  EXPECT_EQ(text.find("GigE Vision camera SIM-CAM-LOWER at 127.0.0.1: 0 frames"), std::string::npos)
      << text;
  EXPECT_NE(text.find("GigE Vision camera SIM-CAM-LOWER at 127.0.0.1: "), std::string::npos)
      << text;
}

// Whether the simulated DSLR serving `port` ("disk:<folder>") accepts a connection.
bool DslrAccepts(const std::string& port) {
  const std::string path = port.substr(5) + "/camera.sock";
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::snprintf(address.sun_path, sizeof address.sun_path, "%s", path.c_str());
  const bool ok =
      fd >= 0 && connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  if (fd >= 0) close(fd);
  return ok;
}

// One GVCP packet at 0xFFFFFFF0 crashed Aravis' GigE fake and took the
// Modbus and DSLR simulators of `sim serve` down with it.
TEST(Cli, SimServeSurvivesHostileGigEControlPackets) {
  SimServe serve;
  StartSimServe("sim_serve_hostile", &serve);
  ASSERT_GT(serve.pid, 0);
  ASSERT_FALSE(serve.modbus_port.empty()) << "no endpoint printed:\n" << ReadText(serve.log);
  std::this_thread::sleep_for(
      std::chrono::milliseconds(200));  // every simulator printed and serving
  for (const auto& packet : hairrig_test::HostileGvcpPackets())
    hairrig_test::AskGvcp("127.0.0.1", packet, 100);
  EXPECT_EQ(waitpid(serve.pid, nullptr, WNOHANG), 0) << "sim serve died:\n" << ReadText(serve.log);
  const auto read_test_register =
      hairrig_test::GvcpCommand(hairrig_test::kGvcpReadRegister, {hairrig_test::kFakeTestRegister});
  EXPECT_EQ(hairrig_test::AskGvcp("127.0.0.1", read_test_register), 12);
  const std::string mbpoll = "mbpoll -m tcp -p " + serve.modbus_port +
                             " -a 1 -0 -1 -t 4:hex -r 100 -c 2 127.0.0.1 > /dev/null";
  EXPECT_EQ(std::system(mbpoll.c_str()), 0) << mbpoll;
  const std::string text = ReadText(serve.log);
  const size_t disk = text.find("--port disk:");
  ASSERT_NE(disk, std::string::npos) << text;
  const std::string dslr_port =
      text.substr(disk + 7, text.find_first_of(" \n", disk + 7) - disk - 7);
  EXPECT_TRUE(DslrAccepts(dslr_port)) << dslr_port;
  EXPECT_EQ(StopSimServe(&serve), 0);
}

}  // namespace

namespace capture_cli {

namespace fs = std::filesystem;

// The JSON summary is the last line of the output (logs go to stderr before it).
std::string FreshPath(const std::string& name) {
  const std::string path = ::testing::TempDir() + "/cli_" + name;
  fs::remove_all(path);
  return path;
}

// A new user's first capture: only --out, the default (simulated) rig.
TEST(CliCapture, OutIsTheOnlyFlagANewUserNeeds) {
  const std::string out = FreshPath("first_capture");
  const CommandRun r = Hairrig("--log-level warning capture --out " + out + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = LastLineJson(r.output);
  for (const char* key : {"views_planned", "views_completed", "frames", "bytes", "wall_s",
                          "lower_bound_s", "efficiency"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["views_planned"], 38);
  EXPECT_EQ(j["views_completed"], 38);
  EXPECT_EQ(j["frames"], 38);
  EXPECT_TRUE(fs::exists(out + "/frames/037_SIM-CAM-LOWER.png"));
}

TEST(CliCapture, SubjectFolderResumeAndReplay) {
  const std::string root = FreshPath("subjects");
  const std::string small = "--config tests/data/small_rig.yaml";
  CommandRun r = Hairrig("--log-level warning capture " + small + " --out " + root +
                         " --subject 'Wig 03' --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string capture = root + "/Wig_03";
  EXPECT_EQ(LastLineJson(r.output)["dir"], fs::absolute(capture).lexically_normal().string());
  EXPECT_EQ(nlohmann::json::parse(ReadText(capture + "/manifest.json"))["subject"], "Wig 03");

  r = Hairrig("capture " + small + " --out " + root + " --subject 'Wig 03'");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--resume"), std::string::npos) << r.output;

  r = Hairrig("--log-level warning capture --out " + capture + " --resume --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(LastLineJson(r.output)["views_kept"], 38);
  EXPECT_EQ(LastLineJson(r.output)["frames"], 0);

  r = Hairrig("--log-level warning replay " + capture + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(LastLineJson(r.output)["views_completed"], 38);
  EXPECT_TRUE(fs::exists(capture + "-replay/manifest.json"));
}

TEST(CliCapture, UnsafeSubjectsAreRefusedAndNothingIsWritten) {
  const std::string root = FreshPath("unsafe");
  for (const std::string subject : {"../x", "/tmp/abs", "$'a\\nb'", "'.hidden'"}) {
    const CommandRun r = Hairrig("capture --config tests/data/small_rig.yaml --out " + root +
                                 " --subject " + subject);
    EXPECT_EQ(r.exit_code, 1) << subject << ": " << r.output;
    EXPECT_NE(r.output.find("subject name"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(root));
}

TEST(CliCapture, ResumeOfAFolderThatIsNoCaptureIsRefused) {
  const std::string dir = FreshPath("not_a_capture");
  fs::create_directories(dir);
  const CommandRun r = Hairrig("capture --out " + dir + " --resume");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("not a capture folder"), std::string::npos) << r.output;
}

// Twelve curls as an ASCII PLY strand file (vertex + strand element).
std::string CurlsPly() {
  std::string text =
      "ply\nformat ascii 1.0\nelement vertex 480\nproperty float x\nproperty float y\n"
      "property float z\nelement strand 12\nproperty ushort nsegs\nend_header\n";
  for (int s = 0; s < 12; ++s) {
    for (int k = 0; k < 40; ++k) {
      const double a = 0.3 * k;
      text += std::to_string(20 * (s % 4) + 5 * std::cos(a)) + " " +
              std::to_string(20 * (s / 4) + 5 * std::sin(a)) + " " + std::to_string(-0.8 * k) +
              "\n";
    }
  }
  for (int s = 0; s < 12; ++s) text += "39\n";
  return TempFile("curls.ply", text);
}

TEST(CliFit, FitsStrandsAndRefusesBadInput) {
  const std::string strands = CurlsPly();
  const std::string out = FreshPath("model.json");
  CommandRun r = Hairrig("fit " + strands + " --out " + out + " --guides 4 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = LastLineJson(r.output);
  EXPECT_EQ(j["guides"], 4);
  EXPECT_LT(j["mean_error_mm"].get<double>(), 0.5);
  EXPECT_LT(j["max_g1_defect_deg"].get<double>(), 1e-3);
  ASSERT_TRUE(j.contains("max_relaxation_elements")) << r.output;
  EXPECT_LT(j["max_relaxation_elements"].get<double>(), 0.25)
      << "no resonance of the relaxation on these curls";
  EXPECT_TRUE(fs::exists(out));
  r = Hairrig("fit " + strands + " --out " + out + " --guides 1000");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("more than the 12 strands"), std::string::npos) << r.output;
  const std::string broken = TempFile("broken.hair", "not a hair file");
  r = Hairrig("fit " + broken + " --out " + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("broken.hair"), std::string::npos) << r.output;
}

TEST(CliSimulate, WritesFramesPreviewsAndSummaryAndRefusesBadInput) {
  const std::string strands = CurlsPly();
  const std::string model = FreshPath("sim_model.json");
  ASSERT_EQ(Hairrig("fit " + strands + " --out " + model + " --guides 4").exit_code, 0);
  const std::string out = FreshPath("sim_out");
  CommandRun r =
      Hairrig("simulate " + model + " --out " + out +
              " --scenario wind --seconds 0.2 --fps 10 --no-head --preview-every 2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = LastLineJson(r.output);
  EXPECT_EQ(j["frames"], 3);
  EXPECT_EQ(j["guides"], 4);
  EXPECT_EQ(j["strands"], 12) << "every strand of the source, interpolated from the guides";
  EXPECT_GT(j["max_tip_move_mm"].get<double>(), 0.0);
  for (const char* f : {"frames/frame_0000.hair", "frames/frame_0002.hair",
                        "previews/frame_0000.png", "previews/frame_0002.png", "summary.json"}) {
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
  }
  EXPECT_FALSE(fs::exists(out + "/previews/frame_0001.png"));

  r = Hairrig("simulate " + model + " --out " + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("already exists"), std::string::npos) << r.output;
  r = Hairrig("simulate " + model + " --out " + FreshPath("sim_bad") + " --scenario tornado");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("unknown scenario 'tornado'"), std::string::npos) << r.output;

  nlohmann::json doc = nlohmann::json::parse(ReadText(model));
  doc["version"] = 99;
  const std::string old_version = TempFile("old_model.json", doc.dump());
  r = Hairrig("simulate " + old_version + " --out " + FreshPath("sim_old"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("model version 99"), std::string::npos) << r.output;

  doc = nlohmann::json::parse(ReadText(model));
  doc["guides"][0]["elements"][0]["length_mm"] = -1;
  const std::string degenerate = TempFile("degenerate_model.json", doc.dump());
  r = Hairrig("simulate " + degenerate + " --out " + FreshPath("sim_degenerate"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("guides[0].elements[0]"), std::string::npos) << r.output;
}

}  // namespace capture_cli
