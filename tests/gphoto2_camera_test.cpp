// The `gphoto2` camera backend against the simulated DSLR, through the
// unmodified libgphoto2 loading the project's camlib (CAMLIBS); and the
// simulated DSLR against an independent client, the `gphoto2` command.
#include "drivers/gphoto2_camera.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "core/clock.h"
#include "sim_hw/scene.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_dslr_protocol.h"
#include "sim_hw/sim_dslr_server.h"
#include "tests/support/camera_checks.h"
#include "tests/support/sim_world.h"

namespace hairrig {
namespace {

using hairrig_test::ArmOnLine;
using hairrig_test::kFrameWait;
using hairrig_test::Psnr;
using hairrig_test::ShootOnce;

using std::chrono::milliseconds;
constexpr char kSerial[] = "SIM-CAM-UPPER";

struct Bench {
  std::shared_ptr<SimWorld> world;  // with its panels on, so that the views are lit
  std::unique_ptr<SimDslrServer> server;
  std::unique_ptr<Camera> camera;
};

Gphoto2CameraOptions ClientOptions(const SimDslrServer& server) {
  Gphoto2CameraOptions o;
  o.port = server.port();
  o.model = sim_dslr::kModel;
  o.nominal.width_px = 1200;
  o.nominal.height_px = 1600;
  o.nominal.time_scale = 0.01;
  o.busy_backoff_s = 0.5;  // x time_scale
  return o;
}

// `reply_timeout_ms`: how long the camlib waits for any reply; generous, since
// a CAPTURE reply waits for the render (seconds in a sanitizer build).
Bench StartBench(std::vector<SimFault> faults = {}, const std::string& trigger_line = "",
                 int reply_timeout_ms = 60000) {
  Bench b;
  b.world = hairrig_test::MakeSimWorld(std::move(faults), /*lights_on=*/true);
  EXPECT_TRUE(ExportSimDslrCamlibs().ok());
  SimDslrOptions options;
  options.serial = kSerial;
  options.scene_camera = 0;
  options.trigger_line = trigger_line;
  options.reply_timeout_ms = reply_timeout_ms;
  auto server = SimDslrServer::Start(b.world, options);
  EXPECT_TRUE(server.ok()) << server.status().ToString();
  b.server = std::move(server).value();
  b.camera = MakeGphoto2Camera({DeviceKind::kCamera, "upper", "gphoto2", kSerial, "test DSLR"},
                               ClientOptions(*b.server));
  return b;
}

// A killed process leaves its port folder, socket and all; the next server
// to start removes such folders whose owner is gone, and no other.
TEST(SimDslrServer, RemovesTheFoldersKilledProcessesLeft) {
  namespace fs = std::filesystem;
  const fs::path parent =
      fs::path(::testing::TempDir()) / ("dslr_stale_" + std::to_string(getpid()));
  fs::remove_all(parent);
  fs::create_directories(parent);
  const pid_t gone = fork();
  if (gone == 0) _exit(0);
  ASSERT_EQ(waitpid(gone, nullptr, 0), gone);
  const auto leave = [&](const std::string& name, pid_t owner) {
    fs::create_directories(parent / name);
    std::ofstream(parent / name / sim_dslr::kSocketName) << "";  // nothing listens on it
    if (owner != 0) std::ofstream(parent / name / "owner.pid") << owner << "\n";
  };
  leave("hairrig-dslr-killed", gone);
  leave("hairrig-dslr-running", getpid());
  leave("hairrig-dslr-no-owner", 0);
  leave("another-folder", gone);
  const std::string tmpdir = std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "";
  setenv("TMPDIR", parent.c_str(), 1);
  SimDslrOptions options;
  options.serial = kSerial;
  auto server = SimDslrServer::Start(hairrig_test::MakeSimWorld(), options);
  if (tmpdir.empty()) {
    unsetenv("TMPDIR");
  } else {
    setenv("TMPDIR", tmpdir.c_str(), 1);
  }
  ASSERT_TRUE(server.ok()) << server.status().ToString();
  EXPECT_FALSE(fs::exists(parent / "hairrig-dslr-killed"));
  for (const char* kept : {"hairrig-dslr-running", "hairrig-dslr-no-owner", "another-folder"}) {
    EXPECT_TRUE(fs::exists(parent / kept)) << kept;
  }
  const fs::path own = (*server)->folder();
  EXPECT_EQ(own.parent_path(), parent);
  std::ifstream owner(own / "owner.pid");
  pid_t recorded = 0;
  EXPECT_TRUE(owner >> recorded);
  EXPECT_EQ(recorded, getpid());
  (*server)->Stop();
  EXPECT_FALSE(fs::exists(own));
  fs::remove_all(parent);
}

TEST(Gphoto2Camera, OpensBySerialShootsAndDownloadsTheRenderedView) {
  Bench b = StartBench();
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(b.camera->HealthCheck().ok());
  const WorldExposure exposure = ExposeWorldNow(*b.world);
  auto frame = ShootOnce(*b.camera, PixelFormat::kRgb8, 0.02, 6.0);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_EQ(frame->format, PixelFormat::kEncoded);
  EXPECT_EQ(frame->encoding, "jpg");
  EXPECT_EQ(frame->camera_serial, kSerial);
  EXPECT_NEAR(frame->exposure_s, 0.02, 1e-9);  // "1/50" is a choice
  EXPECT_GE(frame->trigger_time_ns, exposure.trigger_ns);
  EXPECT_GT(frame->received_time_ns, frame->trigger_time_ns);
  const cv::Mat decoded = cv::imdecode(frame->data, cv::IMREAD_COLOR);
  ASSERT_EQ(decoded.cols, 1200);
  ASSERT_EQ(decoded.rows, 1600);
  // The JPEG is the scene camera's view at gain 6 dB (ISO 200): compare with a direct render.
  auto reference = RenderWorldExposure(*b.world, 0, exposure, 0.02, 20 * std::log10(2.0), 0);
  ASSERT_TRUE(reference.ok());
  EXPECT_GT(Psnr(decoded, *reference), 35.0);
  auto darker = RenderWorldExposure(*b.world, 0, exposure, 0.02, 0.0, 0);
  EXPECT_LT(Psnr(decoded, *darker), Psnr(decoded, *reference) - 6.0);
  EXPECT_GT(cv::mean(decoded)[1], 20.0);  // lit, not a black frame
  EXPECT_EQ(b.server->shots(), 1);
}

TEST(Gphoto2Camera, LiveViewFramesAreSmallViewsOfTheSceneAndFireNoShot) {
  Bench b = StartBench();
  ASSERT_TRUE(b.camera->Open().ok());
  CaptureSettings s;
  s.exposure_s = 0.02;
  s.gain_db = 6.0;
  ASSERT_TRUE(b.camera->Configure(s).ok());
  const WorldExposure exposure = ExposeWorldNow(*b.world);
  auto frame = b.camera->CapturePreview(kFrameWait);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_EQ(frame->format, PixelFormat::kEncoded);
  const cv::Mat decoded = cv::imdecode(frame->data, cv::IMREAD_COLOR);
  ASSERT_EQ(decoded.cols, 640);
  ASSERT_EQ(decoded.rows, 853);
  auto reference = RenderWorldExposure(*b.world, 0, exposure, 0.02, 20 * std::log10(2.0), 0);
  ASSERT_TRUE(reference.ok());
  cv::Mat small;
  cv::resize(*reference, small, decoded.size(), 0, 0, cv::INTER_AREA);
  EXPECT_GT(Psnr(decoded, small), 30.0);
  EXPECT_EQ(b.server->shots(), 0) << "live view fires no shutter and stores no file";
  // Armed for shots, the body takes no live-view request.
  ASSERT_TRUE(b.camera->Arm().ok());
  EXPECT_EQ(b.camera->CapturePreview(kFrameWait).status().code(), StatusCode::kFailedPrecondition);
}

TEST(Gphoto2Camera, SecondShotIsNumberedOnAndTheCardIsEmptiedAfterDownload) {
  Gphoto2CameraOptions o;
  Bench b = StartBench();
  o = ClientOptions(*b.server);
  o.settings = {{"capturetarget", "Memory card"}, {"imageformat", "Large Normal JPEG"}};
  b.camera = MakeGphoto2Camera({DeviceKind::kCamera, "upper", "gphoto2", kSerial, "test DSLR"}, o);
  ASSERT_TRUE(b.camera->Open().ok());
  CaptureSettings s;
  ASSERT_TRUE(b.camera->Configure(s).ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  auto first = b.camera->WaitFrame(kFrameWait);
  auto second = b.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(first.ok() && second.ok());
  EXPECT_EQ(first->sequence, 0u);
  EXPECT_EQ(second->sequence, 1u);
  EXPECT_LE(first->trigger_time_ns, second->trigger_time_ns);
  EXPECT_EQ(b.server->shots(), 2);
  // Deleted after download even on the memory card: a third wait finds nothing.
  EXPECT_EQ(b.camera->WaitFrame(milliseconds(200)).status().code(), StatusCode::kTimeout);
}

TEST(Gphoto2Camera, SettingsOutsideTheChoicesAreRefusedWithTheChoices) {
  Bench b = StartBench();
  Gphoto2CameraOptions o = ClientOptions(*b.server);
  o.settings = {{"iso", "300"}};
  auto bad = MakeGphoto2Camera({DeviceKind::kCamera, "upper", "gphoto2", kSerial, "test DSLR"}, o);
  Status s = bad->Open();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.ToString();
  EXPECT_NE(s.message().find("settings.iso"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("100, 200, 400"), std::string::npos) << s.message();
  bad.reset();  // releases the camera

  o.settings = {{"whitebalance", "Daylight"}};
  auto unknown =
      MakeGphoto2Camera({DeviceKind::kCamera, "upper", "gphoto2", kSerial, "test DSLR"}, o);
  s = unknown->Open();
  EXPECT_NE(s.message().find("no setting named 'whitebalance'"), std::string::npos) << s.message();
}

TEST(Gphoto2Camera, AnotherSerialAtThePortIsRefusedNamingBoth) {
  Bench b = StartBench();
  auto other =
      MakeGphoto2Camera({DeviceKind::kCamera, "lower", "gphoto2", "SIM-CAM-LOWER", "test DSLR"},
                        ClientOptions(*b.server));
  const Status s = other->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable);
  EXPECT_NE(s.message().find("SIM-CAM-UPPER"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("SIM-CAM-LOWER"), std::string::npos) << s.message();
}

TEST(Gphoto2Camera, ALinePulseFiresTheShutterAndTheFileArrivesAsAnEvent) {
  Bench b = StartBench({}, "trig0");
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(ArmOnLine(*b.camera, "trig0").ok());
  EXPECT_EQ(b.camera->WaitFrame(milliseconds(100)).status().code(), StatusCode::kTimeout);
  WorldTriggers(*b.world).Fire("trig0");
  auto frame = b.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_FALSE(frame->data.empty());
  EXPECT_LE(frame->trigger_time_ns, frame->received_time_ns);
}

// Line pulses the host notes are the frames' trigger times, in order: a shot
// that comes out after its wait timed out carries its own pulse's time.
TEST(Gphoto2Camera, ALateShotCarriesTheTimeOfItsOwnPulse) {
  // The 1st shot takes 100 device s (1 s here) longer than usual.
  Bench b = StartBench({SimFault{SimFaultKind::kDownloadTimeout, kSerial, 0, 1, 100.0}}, "trig0");
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(ArmOnLine(*b.camera, "trig0").ok());
  const int64_t first_ns = SteadyNowNs();
  b.camera->LineTriggerSent(first_ns);
  WorldTriggers(*b.world).Fire("trig0");
  EXPECT_EQ(b.camera->WaitFrame(milliseconds(200)).status().code(), StatusCode::kTimeout);
  const int64_t second_ns = SteadyNowNs();
  b.camera->LineTriggerSent(second_ns);
  WorldTriggers(*b.world).Fire("trig0");
  auto late = b.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(late.ok()) << late.status().ToString();
  EXPECT_EQ(late->trigger_time_ns, first_ns);
  auto next = b.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(next.ok()) << next.status().ToString();
  EXPECT_EQ(next->trigger_time_ns, second_ns);
}

// A shot still developing when the connection is closed belongs to the old
// session (as with PTP): after reopening and arming, the first frame is the
// new trigger's, not the old shot's.
TEST(Gphoto2Camera, AShotOfAClosedSessionIsNotTakenForTheNextTrigger) {
  Bench b = StartBench({SimFault{SimFaultKind::kDownloadTimeout, kSerial, 0, 1, 50.0}});
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  EXPECT_EQ(b.camera->WaitFrame(milliseconds(100)).status().code(), StatusCode::kTimeout);
  ASSERT_TRUE(b.camera->Close().ok());
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  ASSERT_TRUE(hairrig_test::WaitUntil([&] { return b.server->shots() == 1; }))
      << "the old shot never reached the card";
  const int64_t trigger_ns = SteadyNowNs();
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  auto frame = b.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_GE(frame->trigger_time_ns, trigger_ns);
  EXPECT_EQ(b.camera->WaitFrame(milliseconds(300)).status().code(), StatusCode::kTimeout)
      << "the old session's shot came out";
}

TEST(Gphoto2Camera, ABusyCameraIsRetriedThenReportedBusy) {
  Bench b = StartBench();
  ASSERT_TRUE(b.camera->Open().ok());
  b.server->InjectFault(SimDslrServer::Fault::kBusy, 2);
  auto frame = ShootOnce(*b.camera, PixelFormat::kRgb8);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();  // third attempt succeeds

  ASSERT_TRUE(b.camera->Arm().ok());
  b.server->InjectFault(SimDslrServer::Fault::kBusy, 3);
  const Status s = b.camera->SoftwareTrigger();
  EXPECT_EQ(s.code(), StatusCode::kDeviceFault) << s.ToString();
  EXPECT_NE(s.message().find("busy"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("3 attempts"), std::string::npos) << s.message();
  EXPECT_TRUE(b.camera->SoftwareTrigger().ok());  // still usable
}

TEST(Gphoto2Camera, NoReplyIsATimeoutAndTheCameraStaysUsable) {
  // Long enough that the normal requests around the dropped one are answered on a loaded machine.
  Bench b = StartBench({}, "", /*reply_timeout_ms=*/3000);
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(b.camera->Configure({}).ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  b.server->InjectFault(SimDslrServer::Fault::kNoReply, 1);
  const Status s = b.camera->SoftwareTrigger();
  EXPECT_EQ(s.code(), StatusCode::kTimeout) << s.ToString();
  EXPECT_NE(s.message().find("did not answer"), std::string::npos) << s.message();
  EXPECT_EQ(b.camera->state(), DeviceState::kBusy);
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  EXPECT_TRUE(b.camera->WaitFrame(kFrameWait).ok());
}

TEST(Gphoto2Camera, ACameraHeldByAnotherClientIsReportedClaimed) {
  Bench b = StartBench();
  ASSERT_TRUE(b.camera->Open().ok());
  auto second = MakeGphoto2Camera({DeviceKind::kCamera, "upper2", "gphoto2", kSerial, "test DSLR"},
                                  ClientOptions(*b.server));
  Status s = second->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("claimed by process"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("another process holds the camera"), std::string::npos) << s.message();
  ASSERT_TRUE(b.camera->Close().ok());
  EXPECT_TRUE(second->Open().ok());  // released by the first
}

TEST(Gphoto2Camera, ADroppedCameraFaultsAndReopensWhenItIsBack) {
  // At its 2nd shot the body drops off the bus and stays away for 1 connection attempt.
  Bench b = StartBench({SimFault{SimFaultKind::kCameraGone, kSerial, 2, 1, 0.0}});
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(ShootOnce(*b.camera, PixelFormat::kRgb8).ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  Status s = b.camera->SoftwareTrigger();
  if (s.ok()) s = b.camera->WaitFrame(kFrameWait).status();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("dropped off the bus"), std::string::npos) << s.message();
  EXPECT_EQ(b.camera->state(), DeviceState::kFaulted);
  s = b.camera->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  s = b.camera->Open();
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_TRUE(ShootOnce(*b.camera, PixelFormat::kRgb8).ok());
}

TEST(Gphoto2Camera, ACablePulledMidRequestFaultsAndReopens) {
  Bench b = StartBench();
  ASSERT_TRUE(b.camera->Open().ok());
  b.server->InjectFault(SimDslrServer::Fault::kDisconnect, 1);
  auto frame = ShootOnce(*b.camera, PixelFormat::kRgb8);
  ASSERT_FALSE(frame.ok());
  EXPECT_EQ(frame.status().code(), StatusCode::kUnavailable) << frame.status().ToString();
  ASSERT_TRUE(b.camera->Open().ok());
  EXPECT_TRUE(ShootOnce(*b.camera, PixelFormat::kRgb8).ok());
}

TEST(Gphoto2Camera, NoCameraAtThePortSaysWhatToStart) {
  Bench b = StartBench();
  b.server->Stop();
  const Status s = b.camera->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("sim serve"), std::string::npos) << s.message();
}

TEST(Gphoto2Camera, ConfigErrorsNameTheField) {
  auto root = ConfigNode::LoadString(
      "{name: c, backend: gphoto2, serial: X, port: 'disk:/tmp/x', sttings: {}}", "rig.yaml");
  ASSERT_TRUE(root.ok());
  auto parsed = ParseGphoto2CameraOptions(*root);
  ASSERT_FALSE(parsed.ok());
  EXPECT_NE(parsed.status().message().find("sttings"), std::string::npos)
      << parsed.status().message();
  root = ConfigNode::LoadString("{name: c, backend: gphoto2, serial: X, port: 'disk:/tmp/x'}",
                                "rig.yaml");
  parsed = ParseGphoto2CameraOptions(*root);
  ASSERT_FALSE(parsed.ok());
  EXPECT_NE(parsed.status().message().find("model"), std::string::npos)
      << parsed.status().message();
}

// --- the gphoto2 command against the simulated DSLR ---------------------------

// Runs `command` through the shell; its output, or nullopt (and a failure) when it failed.
std::optional<std::string> RunShell(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return std::nullopt;
  std::string out;
  char buf[4096];
  size_t n = 0;
  while ((n = fread(buf, 1, sizeof(buf), pipe)) > 0) out.append(buf, n);
  if (pclose(pipe) != 0) {
    ADD_FAILURE() << command << " failed:\n" << out;
    return std::nullopt;
  }
  return out;
}

// The unmodified gphoto2 with the simulated DSLR's camlib folder as CAMLIBS.
std::optional<std::string> RunGphoto2(const std::string& args, const std::string& wrapper = "") {
  auto folder = SimDslrCamlibFolder();
  if (!folder.ok()) return std::nullopt;
  return RunShell(wrapper + "env CAMLIBS='" + *folder + "' gphoto2 " + args);
}

class Gphoto2Command : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v gphoto2 >/dev/null 2>&1") != 0) {
      GTEST_FAIL() << "the gphoto2 command is not installed: run scripts/install-deps";
    }
    bench_ = StartBench();
    target_ =
        "--camera '" + std::string(sim_dslr::kModel) + "' --port " + bench_.server->port() + " ";
  }
  Bench bench_;
  std::string target_;
};

TEST_F(Gphoto2Command, ListsTheSimulatedModel) {
  auto out = RunGphoto2("--list-cameras");
  ASSERT_TRUE(out);
  EXPECT_NE(out->find(sim_dslr::kModel), std::string::npos);
  // The system camlibs are linked beside it, so real bodies stay known.
  EXPECT_NE(out->find("Canon EOS 5D Mark IV"), std::string::npos);
}

// libgphoto2 auto-detects USB cameras only. umockdev enumerates a USB device
// with the id the simulated body's camlib claims (tests/data/sim_dslr_usb.umockdev:
// sysfs attributes and descriptors, written for this test), and the unmodified
// gphoto2 lists the simulated model on it.
TEST_F(Gphoto2Command, AutoDetectListsTheSimulatedBodyOnAUsbBus) {
  if (std::system("command -v umockdev-run >/dev/null 2>&1") != 0) {
    GTEST_FAIL() << "umockdev-run is not installed: run scripts/install-deps";
  }
  auto out = RunGphoto2("--auto-detect", "umockdev-run -d tests/data/sim_dslr_usb.umockdev -- ");
  ASSERT_TRUE(out);
  EXPECT_NE(out->find(std::string(sim_dslr::kModel) + " "), std::string::npos) << *out;
  EXPECT_NE(out->find("usb:001,002"), std::string::npos) << *out;
  // Without the USB device, nothing is detected.
  auto plain = RunGphoto2("--auto-detect");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->find(sim_dslr::kModel), std::string::npos) << *plain;
}

TEST_F(Gphoto2Command, CapturesAndDownloadsAJpegOfTheView) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("hairrig-gphoto2-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "shot.jpg").string();
  auto out =
      RunGphoto2(target_ + "--capture-image-and-download --force-overwrite --filename " + file);
  ASSERT_TRUE(out);
  const cv::Mat image = cv::imread(file, cv::IMREAD_COLOR);
  EXPECT_EQ(image.cols, 1200) << *out;
  EXPECT_EQ(image.rows, 1600) << *out;
  EXPECT_EQ(bench_.server->shots(), 1);
  std::filesystem::remove_all(dir);
}

TEST_F(Gphoto2Command, SetConfigIsReadBackByGetConfig) {
  ASSERT_TRUE(RunGphoto2(target_ + "--set-config iso=800 --set-config shutterspeed=1/100"));
  auto iso = RunGphoto2(target_ + "--get-config iso");
  ASSERT_TRUE(iso);
  EXPECT_NE(iso->find("Current: 800"), std::string::npos) << *iso;
  auto serial = RunGphoto2(target_ + "--get-config serialnumber");
  ASSERT_TRUE(serial);
  EXPECT_NE(serial->find(std::string("Current: ") + kSerial), std::string::npos) << *serial;
  // The value refused by the camera is refused by the command too.
  const std::string refused = "env CAMLIBS='" + *SimDslrCamlibFolder() + "' gphoto2 " + target_ +
                              "--set-config iso=123 >/dev/null 2>&1";
  EXPECT_NE(std::system(refused.c_str()), 0);
}

}  // namespace
}  // namespace hairrig
