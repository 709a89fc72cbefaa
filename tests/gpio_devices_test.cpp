// The `gpiod` devices over the simulated GPIO provider, and the real libgpiod
// provider's behaviour on a machine without the requested chip.
#include "drivers/gpio_devices.h"

#include <gtest/gtest.h>

#include <condition_variable>
#include <mutex>
#include <optional>
#include <vector>

#include "sim_hw/sim_gpio.h"

namespace hairrig {
namespace {

using std::chrono::milliseconds;

struct Gpio {
  std::shared_ptr<SimGpioProvider> provider = std::make_shared<SimGpioProvider>();
  DeviceRegistry registry;
  Gpio() {
    provider->AddChip("hairrig-io", 32);
    RegisterGpioBackends(&registry, provider);
  }
  // A device of `kind` from a one-line YAML map.
  template <typename T>
  Result<std::unique_ptr<T>> Make(DeviceKind kind, const std::string& yaml) {
    auto node = ConfigNode::LoadString(yaml, "rig.yaml");
    EXPECT_TRUE(node.ok()) << node.status().ToString();
    DeviceConfig c{kind, node->String("name"), "gpiod", node->String("serial"), *node};
    auto made = registry.Create(c);
    if (!made.ok()) return made.status();
    return std::unique_ptr<T>(static_cast<T*>(std::move(made).value().release()));
  }
};

TEST(GpioDevices, PanelPowerFollowsSetOnAndGoesOffOnClose) {
  Gpio g;
  auto light = g.Make<Light>(
      DeviceKind::kLight, "{name: top, serial: P1, chip: hairrig-io, line: 5, active_low: true}");
  ASSERT_TRUE(light.ok()) << light.status().ToString();
  ASSERT_TRUE((*light)->Open().ok());
  EXPECT_EQ(g.provider->Consumer("hairrig-io", 5), "hairrig top");
  EXPECT_TRUE(g.provider->Level("hairrig-io", 5)) << "active-low: off is a high level";
  ASSERT_TRUE((*light)->SetOn(true).ok());
  EXPECT_FALSE(g.provider->Level("hairrig-io", 5));
  EXPECT_TRUE((*light)->IsOn().value());
  EXPECT_EQ((*light)->SetLevel(0.5).code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ((*light)->SetLevel(2).code(), StatusCode::kOutOfRange);
  ASSERT_TRUE((*light)->Close().ok());
  EXPECT_TRUE(g.provider->Level("hairrig-io", 5)) << "closing switches the panel off";
  EXPECT_EQ(g.provider->Consumer("hairrig-io", 5), "");
}

TEST(GpioDevices, TriggerPulseHasAtLeastTheRequestedWidth) {
  Gpio g;
  auto trig = g.Make<TriggerLine>(DeviceKind::kTriggerLine,
                                  "{name: trig0, serial: T0, chip: gpiochip0, line: 27}");
  ASSERT_TRUE(trig.ok()) << trig.status().ToString();
  ASSERT_TRUE((*trig)->Open().ok());
  ASSERT_TRUE((*trig)->Pulse(std::chrono::microseconds(2000)).ok());
  const auto t = g.provider->Transitions("hairrig-io", 27);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_TRUE(t[0].level);
  EXPECT_FALSE(t[1].level);
  EXPECT_GE(t[1].timestamp_ns - t[0].timestamp_ns, 2000000);
  EXPECT_EQ((*trig)->Pulse(std::chrono::microseconds(0)).code(), StatusCode::kInvalidArgument);
}

// Records what an input line's OnChange callback hears, for a test to wait on.
class EdgeRecorder {
 public:
  explicit EdgeRecorder(InputLine& line) : line_(line) {
    line.OnChange([this](bool active) {
      std::lock_guard<std::mutex> lock(mutex_);
      seen_.push_back(active);
      changed_.notify_all();
    });
  }
  // The n-th level heard (from 1); nullopt when it did not come within 5 s.
  std::optional<bool> Wait(size_t n) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!changed_.wait_for(lock, milliseconds(5000), [&] { return seen_.size() >= n; }))
      return std::nullopt;
    return seen_[n - 1];
  }

  ~EdgeRecorder() { line_.OnChange(nullptr); }

 private:
  InputLine& line_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<bool> seen_;
};

TEST(GpioDevices, SafetyInputReportsEveryEdgeWithItsPolarity) {
  Gpio g;
  auto estop = g.Make<InputLine>(
      DeviceKind::kInputLine,
      "{name: estop, serial: E1, chip: hairrig-io, line: 3, active_low: true, bias: pull_up}");
  ASSERT_TRUE(estop.ok()) << estop.status().ToString();
  ASSERT_TRUE(g.provider->DriveInput("hairrig-io", 3, true).ok());  // released button, pulled up
  ASSERT_TRUE((*estop)->Open().ok());
  EdgeRecorder edges(**estop);
  EXPECT_FALSE((*estop)->IsActive().value());
  ASSERT_TRUE(g.provider->DriveInput("hairrig-io", 3, false).ok());  // pressed: pulls the line low
  EXPECT_EQ(edges.Wait(1), std::optional<bool>(true));
  EXPECT_TRUE((*estop)->IsActive().value());
  ASSERT_TRUE(g.provider->DriveInput("hairrig-io", 3, true).ok());
  EXPECT_EQ(edges.Wait(2), std::optional<bool>(false));
  EXPECT_TRUE((*estop)->Close().ok());
}

// A cut cable or an unplugged chip: the line faults and its callback hears
// `true`, because a safety input that cannot be read counts as pressed.
TEST(GpioDevices, ASafetyInputThatCannotBeReadCountsAsPressed) {
  Gpio g;
  auto estop = g.Make<InputLine>(DeviceKind::kInputLine,
                                 "{name: estop, serial: E1, chip: hairrig-io, line: 4}");
  ASSERT_TRUE(estop.ok()) << estop.status().ToString();
  ASSERT_TRUE((*estop)->Open().ok());
  EdgeRecorder edges(**estop);
  EXPECT_FALSE((*estop)->IsActive().value());
  ASSERT_TRUE(g.provider->BreakLine("hairrig-io", 4, Unavailable("No such device")).ok());
  EXPECT_EQ(edges.Wait(1), std::optional<bool>(true));
  EXPECT_EQ((*estop)->state(), DeviceState::kFaulted);
  EXPECT_FALSE((*estop)->IsActive().ok());
  const std::string said = DescribeSafetyStop(**estop);
  EXPECT_NE(said.find("cannot be read"), std::string::npos) << said;
  EXPECT_NE(said.find("estop"), std::string::npos) << said;
  EXPECT_TRUE((*estop)->Close().ok());
}

TEST(GpioDevices, ALineHeldByAnotherDeviceIsRefusedNamingTheHolder) {
  Gpio g;
  auto a = g.Make<TriggerLine>(DeviceKind::kTriggerLine,
                               "{name: trig0, serial: T0, chip: hairrig-io, line: 4}");
  auto b = g.Make<Light>(DeviceKind::kLight, "{name: top, serial: P1, chip: hairrig-io, line: 4}");
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_TRUE((*a)->Open().ok());
  const Status s = (*b)->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("held by 'hairrig trig0'"), std::string::npos) << s.message();
  EXPECT_EQ((*b)->state(), DeviceState::kFaulted);
  ASSERT_TRUE((*a)->Close().ok());
  EXPECT_TRUE((*b)->Open().ok());
}

TEST(GpioDevices, BadChipLineOrConfigIsNamed) {
  Gpio g;
  auto nochip =
      g.Make<Light>(DeviceKind::kLight, "{name: top, serial: P1, chip: pinctrl-bcm2711, line: 4}");
  ASSERT_TRUE(nochip.ok());
  Status s = (*nochip)->Open();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("gpiochip0 [hairrig-io]"), std::string::npos) << s.message();
  auto far =
      g.Make<Light>(DeviceKind::kLight, "{name: top, serial: P1, chip: hairrig-io, line: 40}");
  s = (*far)->Open();
  EXPECT_EQ(s.code(), StatusCode::kOutOfRange);
  EXPECT_NE(s.message().find("32 lines"), std::string::npos) << s.message();
  auto missing = g.Make<Light>(DeviceKind::kLight, "{name: top, serial: P1, line: 4}");
  EXPECT_NE(missing.status().message().find("chip"), std::string::npos)
      << missing.status().ToString();
  auto bias = g.Make<Light>(DeviceKind::kLight,
                            "{name: top, serial: P1, chip: hairrig-io, line: 4, bias: pull_up}");
  EXPECT_NE(bias.status().message().find("bias"), std::string::npos) << bias.status().ToString();
}

// The real provider, on a chip this machine does not have (the CI machines
// have no GPIO at all): a clear NotFound that says how to list the chips.
TEST(LibgpiodProvider, AnAbsentChipIsNotFoundWithAHint) {
  auto provider = MakeLibgpiodProvider();
  GpioLineRequest r;
  r.chip = "hairrig-no-such-chip";
  r.offset = 3;
  r.consumer = "test";
  auto out = provider->RequestOutput(r);
  ASSERT_FALSE(out.ok());
  EXPECT_EQ(out.status().code(), StatusCode::kNotFound);
  EXPECT_NE(out.status().message().find("'hairrig-no-such-chip'"), std::string::npos)
      << out.status().ToString();
  EXPECT_NE(out.status().message().find("gpiodetect"), std::string::npos)
      << out.status().ToString();
  EXPECT_FALSE(provider->RequestInput(r).ok());
}

}  // namespace
}  // namespace hairrig
