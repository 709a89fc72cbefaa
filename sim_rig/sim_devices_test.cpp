// The simulated devices behind the driver interfaces, built from etc/sim-rig.yaml
// as the CLI builds them.
#include <gtest/gtest.h>

#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "rig/rig_config.h"
#include "sim_rig/sim_rig.h"
#include "tests/support/camera_checks.h"

namespace hairrig {
namespace {

// The rigs these tests build are simulated ones (sim_rig/sim_rig.h).
[[maybe_unused]] const bool kSimRigRegistered = (RegisterSimRig(), true);

using std::chrono::milliseconds;
// A liveness bound, not a speed check: sanitizer builds render slowly.
constexpr milliseconds kFrameWait{180000};

std::unique_ptr<Rig> OpenDefaultRig() {
  auto config = LoadRigConfig("etc/sim-rig.yaml");
  EXPECT_TRUE(config.ok()) << config.status().ToString();
  auto rig = BuildRig(*config);
  EXPECT_TRUE(rig.ok()) << rig.status().ToString();
  EXPECT_TRUE((*rig)->devices.OpenAll().ok());
  return std::move(rig).value();
}

// Mean grey level; an encoded frame (the gphoto2 camera's JPEG) is decoded first.
double MeanDn(const Frame& f) {
  if (f.format == PixelFormat::kEncoded)
    return cv::mean(cv::imdecode(f.data, cv::IMREAD_GRAYSCALE))[0];
  return std::accumulate(f.data.begin(), f.data.end(), 0.0) / static_cast<double>(f.data.size());
}

// A rig built from a config text whose sim scene is etc/scenes/default.yaml.
std::unique_ptr<Rig> OpenRigFromText(const std::string& devices_yaml) {
  auto root = ConfigNode::LoadString(
      "name: t\nsim: {scene: scenes/default.yaml}\ndevices:\n" + devices_yaml, "etc/test-rig.yaml");
  EXPECT_TRUE(root.ok()) << root.status().ToString();
  RigConfig config;
  config.path = "etc/test-rig.yaml";
  config.relative_to = "etc";  // sim.scene resolves against it
  config.root = *root;
  auto rig = BuildRig(config);
  EXPECT_TRUE(rig.ok()) << rig.status().ToString();
  EXPECT_TRUE((*rig)->devices.OpenAll().ok());
  return std::move(rig).value();
}

// The in-process `sim` turntable, and the default rig's (the `modbus` driver
// talking to the simulated controller), behave alike.
class SimTurntableTest : public ::testing::TestWithParam<std::string> {};

TEST_P(SimTurntableTest, ReachesItsTargetAfterTheProfileAndSettle) {
  auto rig = GetParam() == "default"
                 ? OpenDefaultRig()
                 : OpenRigFromText(
                       "  turntable: {name: t, backend: sim, serial: SIM-TT-0001}\n"
                       "  cameras: [{name: c, backend: sim, serial: SIM-CAM-UPPER}]\n");
  Turntable& tt = *rig->devices.turntable;
  EXPECT_EQ(tt.info().backend, GetParam() == "default" ? "modbus" : "sim");
  ASSERT_TRUE(tt.Home(milliseconds(5000)).ok());
  ASSERT_TRUE(tt.StartMove(90.0, {30.0, 60.0}).ok());
  auto moving = tt.ReadStatus();
  ASSERT_TRUE(moving.ok());
  EXPECT_FALSE(moving->in_position);
  EXPECT_EQ(tt.state(), DeviceState::kBusy);
  ASSERT_TRUE(tt.WaitInPosition(milliseconds(5000)).ok());
  auto there = tt.ReadStatus();
  EXPECT_TRUE(there->in_position);
  EXPECT_NEAR(there->position_deg, 90.0, 1e-9);
  EXPECT_EQ(tt.StartMove(10.0, {1000.0, 60.0}).code(), StatusCode::kOutOfRange);
  // A move of 4 simulated seconds (at time_scale 0.01: 40 ms) cannot be waited for in 1 ms.
  ASSERT_TRUE(tt.StartMove(0.0, {30.0, 60.0}).ok());
  EXPECT_EQ(tt.WaitInPosition(milliseconds(1)).code(), StatusCode::kTimeout);
}

INSTANTIATE_TEST_SUITE_P(Backends, SimTurntableTest, ::testing::Values("default", "sim"));

TEST(SimDevices, OneTriggerPulseExposesEveryCameraOnTheLineAtOnce) {
  auto rig = OpenDefaultRig();
  for (auto& light : rig->devices.lights) ASSERT_TRUE(light->SetOn(true).ok());
  for (auto& cam : rig->devices.cameras) {
    CaptureSettings s;
    s.trigger = TriggerSource::kLine;
    s.trigger_line = "trig0";
    s.format = PixelFormat::kMono8;
    s.exposure_s = 0.02;
    ASSERT_TRUE(cam->Configure(s).ok());
    ASSERT_TRUE(cam->Arm().ok());
  }
  ASSERT_TRUE(rig->devices.trigger_lines[0]->Pulse(std::chrono::microseconds(100)).ok());
  for (auto& cam : rig->devices.cameras) {
    auto frame = cam->WaitFrame(kFrameWait);
    ASSERT_TRUE(frame.ok()) << frame.status().ToString();
    EXPECT_EQ(frame->camera_serial, cam->info().serial);
    if (frame->format == PixelFormat::kEncoded) {
      EXPECT_EQ(cam->info().backend, "gphoto2");  // the body's JPEG
      EXPECT_EQ(cv::imdecode(frame->data, cv::IMREAD_GRAYSCALE).cols, 1200);
    } else {
      EXPECT_EQ(frame->data.size(), frame->ExpectedBytes());
    }
    EXPECT_EQ(frame->width_px, 1200);
    EXPECT_GT(MeanDn(*frame), 20.0);
    // Nothing more was triggered.
    EXPECT_EQ(cam->WaitFrame(milliseconds(50)).status().code(), StatusCode::kTimeout);
  }
}

TEST(SimDevices, LightsOffGiveADarkFrame) {
  auto rig = OpenDefaultRig();
  Camera& cam = *rig->devices.cameras[0];
  CaptureSettings s;
  s.format = PixelFormat::kMono8;
  ASSERT_TRUE(cam.Configure(s).ok());
  ASSERT_TRUE(cam.Arm().ok());
  for (auto& light : rig->devices.lights) ASSERT_TRUE(light->SetOn(false).ok());
  ASSERT_TRUE(cam.SoftwareTrigger().ok());
  auto dark = cam.WaitFrame(kFrameWait);
  for (auto& light : rig->devices.lights) ASSERT_TRUE(light->SetOn(true).ok());
  ASSERT_TRUE(cam.SoftwareTrigger().ok());
  auto lit = cam.WaitFrame(kFrameWait);
  ASSERT_TRUE(dark.ok() && lit.ok());
  std::printf("mean DN: dark %.2f, lit %.2f\n", MeanDn(*dark), MeanDn(*lit));
  EXPECT_LT(MeanDn(*dark), 2.0);
  EXPECT_GT(MeanDn(*lit), 10 * MeanDn(*dark) + 20);
}

TEST(SimDevices, CallsInTheWrongStateExplainTheRemedy) {
  auto config = LoadRigConfig("etc/sim-rig.yaml");
  auto rig = BuildRig(*config);
  ASSERT_TRUE(rig.ok());
  Camera& cam = *(*rig)->devices.cameras[0];
  const Status s = cam.SoftwareTrigger();
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("SIM-CAM-UPPER"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("call Open first"), std::string::npos) << s.message();
}

TEST(SimDevices, ACameraSerialTheSceneDoesNotHaveIsRefused) {
  auto root = ConfigNode::LoadString(
      "name: t\nsim: {scene: scenes/default.yaml}\ndevices:\n  cameras:\n    - {name: c, backend: "
      "sim, serial: NOPE}\n",
      "etc/test-rig.yaml");
  ASSERT_TRUE(root.ok());
  RigConfig config;
  config.path = "etc/test-rig.yaml";
  config.relative_to = "etc";  // sim.scene resolves against it
  config.root = *root;
  auto rig = BuildRig(config);
  ASSERT_FALSE(rig.ok());
  EXPECT_NE(rig.status().message().find("no camera with serial 'NOPE'"), std::string::npos)
      << rig.status().ToString();
  EXPECT_NE(rig.status().message().find("devices.cameras[0]"), std::string::npos)
      << rig.status().ToString();
}

// `device: sim` gives a v4l2 camera a fake UVC camera behind its system-call layer.
TEST(SimDevices, AUvcCameraOnTheSimulatedRig) {
  auto rig = OpenRigFromText(
      "  cameras: [{name: uvc, backend: v4l2, serial: SIM-CAM-LOWER, device: sim}]\n");
  Camera& cam = *rig->devices.cameras[0];
  EXPECT_EQ(cam.capabilities().width_px, 1200);  // the scene camera's size
  auto frame = hairrig_test::ShootOnce(cam, PixelFormat::kMono8);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_EQ(frame->data.size(), frame->ExpectedBytes());
}

// `bus: sim` gives a usbrelay light a simulated board whose channel powers the scene light.
TEST(SimDevices, RelaySwitchedPanelsLightTheView) {
  auto rig = OpenRigFromText(
      "  lights:\n"
      "    - {name: top, backend: usbrelay, serial: PANEL-1, board: RLY01, channel: 1, bus: sim}\n"
      "    - {name: lower_panel, backend: usbrelay, serial: PANEL-2, board: RLY01, channel: 2, "
      "bus: sim, light: bottom}\n"
      "  cameras: [{name: c, backend: sim, serial: SIM-CAM-UPPER}]\n");
  Camera& cam = *rig->devices.cameras[0];
  auto dark = hairrig_test::ShootOnce(cam, PixelFormat::kMono8);
  for (auto& light : rig->devices.lights) ASSERT_TRUE(light->SetOn(true).ok());
  auto lit = hairrig_test::ShootOnce(cam, PixelFormat::kMono8);
  ASSERT_TRUE(dark.ok() && lit.ok());
  EXPECT_LT(MeanDn(*dark), 2.0);
  EXPECT_GT(MeanDn(*lit), 20.0);
}

// `light:` names the scene light of a simulated board's channel: a board on the USB has none.
TEST(SimDevices, ASceneLightNeedsTheSimulatedRelayBus) {
  auto root = ConfigNode::LoadString(
      "name: t\nsim: {scene: scenes/default.yaml}\ndevices:\n"
      "  lights:\n"
      "    - {name: top, backend: usbrelay, serial: PANEL-1, board: RLY01, channel: 1, light: "
      "top}\n"
      "  cameras: [{name: c, backend: sim, serial: SIM-CAM-UPPER}]\n",
      "etc/test-rig.yaml");
  ASSERT_TRUE(root.ok());
  RigConfig config;
  config.path = "etc/test-rig.yaml";
  config.relative_to = "etc";
  config.root = *root;
  auto rig = BuildRig(config);
  ASSERT_FALSE(rig.ok());
  EXPECT_NE(rig.status().message().find("only with bus: sim"), std::string::npos)
      << rig.status().ToString();
  EXPECT_NE(rig.status().message().find("devices.lights[0].light"), std::string::npos)
      << rig.status().ToString();
}

// etc/rig-example.yaml documents a real rig; it must stay a valid config.
TEST(SimDevices, TheExampleRealRigConfigBuilds) {
  auto config = LoadRigConfig("etc/rig-example.yaml");
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  auto rig = BuildRig(*config);
  ASSERT_TRUE(rig.ok()) << rig.status().ToString();
  const DeviceInfo& tt = (*rig)->devices.turntable->info();
  EXPECT_EQ(tt.backend, "modbus");
  EXPECT_NE(tt.model.find("tcp 192.168.10.20:502 unit 1"), std::string::npos) << tt.model;
  EXPECT_EQ((*rig)->devices.lights[0]->info().backend, "gpiod");
  EXPECT_NE((*rig)->devices.input_lines[0]->info().model.find("line 23 of pinctrl-bcm2711"),
            std::string::npos);
  EXPECT_EQ((*rig)->devices.cameras[0]->info().backend, "gphoto2");
  EXPECT_EQ((*rig)->devices.cameras[1]->info().backend, "aravis");
}

TEST(SimDevices, ASimulatedModbusControllerNeedsTheSimSection) {
  auto root = ConfigNode::LoadString(
      "name: t\ndevices:\n  turntable: {name: t, backend: modbus, serial: TT-1, host: sim}\n"
      "  cameras: [{name: c, backend: sim, serial: C}]\n",
      "etc/test-rig.yaml");
  ASSERT_TRUE(root.ok());
  RigConfig config;
  config.path = "etc/test-rig.yaml";
  config.root = *root;
  auto rig = BuildRig(config);
  ASSERT_FALSE(rig.ok());
  EXPECT_NE(rig.status().message().find("host 'sim' needs the rig config's sim section"),
            std::string::npos)
      << rig.status().ToString();
}

}  // namespace
}  // namespace hairrig
