// The state tables of the device interfaces (drivers/device.h), enforced by the
// interfaces themselves: fake backends whose hooks only record that they ran.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "drivers/camera.h"
#include "drivers/turntable.h"

namespace hairrig {
namespace {

// A camera whose hooks record their names; DoOpen marks it ready, as every backend's does.
class FakeCamera : public Camera {
 public:
  FakeCamera()
      : Camera(DeviceInfo{.kind = DeviceKind::kCamera,
                          .name = "upper",
                          .backend = "fake",
                          .serial = "CAM-7",
                          .model = "fake camera"}) {}
  CameraCapabilities capabilities() const override { return {}; }
  // An I/O failure as a backend reports it.
  void Unplug() { (void)Fault(Unavailable("unplugged")); }

  std::vector<std::string> hooks;

 protected:
  Status DoOpen() override {
    hooks.push_back("DoOpen");
    SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status DoClose() override { return Record("DoClose"); }
  Status DoHealthCheck() override { return Record("DoHealthCheck"); }
  Status DoConfigure(const CaptureSettings&) override { return Record("DoConfigure"); }
  Status DoArm() override { return Record("DoArm"); }
  Status DoDisarm() override { return Record("DoDisarm"); }
  Status DoSoftwareTrigger() override { return Record("DoSoftwareTrigger"); }
  void DoLineTriggerSent(int64_t) override { hooks.push_back("DoLineTriggerSent"); }
  Result<Frame> DoWaitFrame(std::chrono::milliseconds) override {
    hooks.push_back("DoWaitFrame");
    return Frame{};
  }
  Result<Frame> DoCapturePreview(std::chrono::milliseconds) override {
    hooks.push_back("DoCapturePreview");
    return Frame{};
  }

 private:
  Status Record(const std::string& hook) {
    hooks.push_back(hook);
    return Status::Ok();
  }
};

// A turntable whose hooks record their names and change no state.
class FakeTurntable : public Turntable {
 public:
  FakeTurntable()
      : Turntable(DeviceInfo{.kind = DeviceKind::kTurntable,
                             .name = "turntable",
                             .backend = "fake",
                             .serial = "TT-1",
                             .model = "fake turntable"}) {}
  TurntableCapabilities capabilities() const override { return {}; }
  // What a backend's move and fault do to the state.
  void Enter(DeviceState s) { SetState(s); }

  std::vector<std::string> hooks;

 protected:
  Status DoOpen() override {
    hooks.push_back("DoOpen");
    SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status DoClose() override { return Record("DoClose"); }
  Status DoHealthCheck() override { return Record("DoHealthCheck"); }
  Status DoHome(std::chrono::milliseconds) override { return Record("DoHome"); }
  Status DoStartMove(double, const MotionProfile&) override { return Record("DoStartMove"); }
  Result<TurntableStatus> DoReadStatus() override {
    hooks.push_back("DoReadStatus");
    return TurntableStatus{};
  }
  Status DoWaitInPosition(std::chrono::milliseconds) override { return Record("DoWaitInPosition"); }
  Status DoStop() override { return Record("DoStop"); }

 private:
  Status Record(const std::string& hook) {
    hooks.push_back(hook);
    return Status::Ok();
  }
};

// The refusal is FailedPrecondition and names the device, the call and the state.
void ExpectRefused(const Status& s, const std::string& device, const std::string& call,
                   const std::string& state) {
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
  EXPECT_NE(s.message().find(device), std::string::npos) << s.message();
  EXPECT_NE(s.message().find(call), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("but it is " + state), std::string::npos) << s.message();
}

constexpr std::chrono::milliseconds kWait{10};

TEST(DeviceState, CallsOnAClosedCameraAreRefusedBeforeTheBackend) {
  FakeCamera camera;
  const std::string device = "camera 'upper' (fake, serial CAM-7)";
  ASSERT_EQ(camera.Describe(), device);
  ExpectRefused(camera.Configure({}), device, "Configure", "closed");
  ExpectRefused(camera.Arm(), device, "Arm", "closed");
  ExpectRefused(camera.SoftwareTrigger(), device, "SoftwareTrigger", "closed");
  ExpectRefused(camera.WaitFrame(kWait).status(), device, "WaitFrame", "closed");
  ExpectRefused(camera.CapturePreview(kWait).status(), device, "CapturePreview", "closed");
  const Status health = camera.HealthCheck();
  ExpectRefused(health, device, "HealthCheck", "closed");
  EXPECT_NE(health.message().find("call Open first"), std::string::npos) << health.message();
  EXPECT_TRUE(camera.hooks.empty()) << "a refused call reached " << camera.hooks.front();
  EXPECT_EQ(camera.state(), DeviceState::kClosed);
}

TEST(DeviceState, TheCameraInterfaceMakesTheArmAndCloseTransitions) {
  FakeCamera camera;
  ASSERT_TRUE(camera.Open().ok());
  EXPECT_EQ(camera.state(), DeviceState::kReady);
  // Ready, not armed: the trigger and the frame wait need busy.
  ExpectRefused(camera.SoftwareTrigger(), camera.Describe(), "SoftwareTrigger", "ready");
  ExpectRefused(camera.WaitFrame(kWait).status(), camera.Describe(), "WaitFrame", "ready");
  EXPECT_EQ(camera.hooks, std::vector<std::string>{"DoOpen"});

  ASSERT_TRUE(camera.Configure({}).ok());
  ASSERT_TRUE(camera.Arm().ok());
  EXPECT_EQ(camera.state(), DeviceState::kBusy) << "DoArm sets no state: Arm does";
  ExpectRefused(camera.Configure({}), camera.Describe(), "Configure", "busy");
  ExpectRefused(camera.CapturePreview(kWait).status(), camera.Describe(), "CapturePreview", "busy");
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  ASSERT_TRUE(camera.WaitFrame(kWait).ok());
  ASSERT_TRUE(camera.Disarm().ok());
  EXPECT_EQ(camera.state(), DeviceState::kReady);
  ASSERT_TRUE(camera.Close().ok());
  EXPECT_EQ(camera.state(), DeviceState::kClosed) << "DoClose sets no state: Close does";
  EXPECT_EQ(camera.hooks,
            (std::vector<std::string>{"DoOpen", "DoConfigure", "DoArm", "DoSoftwareTrigger",
                                      "DoWaitFrame", "DoDisarm", "DoClose"}));
}

TEST(DeviceState, AFaultedCameraIsRefusedUntilReopened) {
  FakeCamera camera;
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Arm().ok());
  camera.Unplug();
  ASSERT_EQ(camera.state(), DeviceState::kFaulted);
  camera.hooks.clear();
  const Result<Frame> frame = camera.WaitFrame(kWait);
  ExpectRefused(frame.status(), camera.Describe(), "WaitFrame", "faulted");
  EXPECT_NE(frame.status().message().find("Close and Open it again"), std::string::npos)
      << frame.status().message();
  EXPECT_TRUE(camera.hooks.empty()) << "a refused call reached " << camera.hooks.front();
  // Close and Open are allowed in any state; Disarm too, and leaves a faulted camera faulted.
  ASSERT_TRUE(camera.Disarm().ok());
  EXPECT_EQ(camera.state(), DeviceState::kFaulted);
  ASSERT_TRUE(camera.Open().ok());
  EXPECT_EQ(camera.state(), DeviceState::kReady);
  EXPECT_TRUE(camera.HealthCheck().ok());
}

TEST(DeviceState, TheTurntableStopsInAnyOpenStateAndMovesOnlyWhenReadyOrBusy) {
  FakeTurntable table;
  const MotionProfile profile{};
  ExpectRefused(table.Stop(), table.Describe(), "Stop", "closed");
  ExpectRefused(table.StartMove(90, profile), table.Describe(), "StartMove", "closed");
  ExpectRefused(table.ReadStatus().status(), table.Describe(), "ReadStatus", "closed");
  EXPECT_TRUE(table.hooks.empty()) << "a refused call reached " << table.hooks.front();

  ASSERT_TRUE(table.Open().ok());
  table.Enter(DeviceState::kBusy);
  ASSERT_TRUE(table.Stop().ok());
  EXPECT_EQ(table.state(), DeviceState::kReady) << "a stopped turntable is ready again";

  table.Enter(DeviceState::kFaulted);
  table.hooks.clear();
  ExpectRefused(table.MoveTo(90, profile, kWait), table.Describe(), "StartMove", "faulted");
  ExpectRefused(table.Home(kWait), table.Describe(), "Home", "faulted");
  EXPECT_TRUE(table.hooks.empty()) << "a refused call reached " << table.hooks.front();
  ASSERT_TRUE(table.ReadStatus().ok());
  ASSERT_TRUE(table.Stop().ok());
  EXPECT_EQ(table.state(), DeviceState::kFaulted) << "a stop does not clear a fault";
  EXPECT_EQ(table.hooks, (std::vector<std::string>{"DoReadStatus", "DoStop"}));
}

}  // namespace
}  // namespace hairrig
