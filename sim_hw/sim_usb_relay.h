// Simulated HID USB relay boards behind the `usbrelay` backend's bus
// interface (drivers/usb_relay.h). Each board answers the feature reports of
// drivers/usb_relay_protocol.h: switch commands change its channel mask, the
// state report gives its id and mask. A channel can power a scene light of
// the simulated world, so the rendered frames show what the relay did.
// Faults: Unplug (every exchange fails Unavailable, the board leaves List)
// and StickChannel (a welded relay: the channel ignores commands).
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "drivers/usb_relay.h"

namespace hairrig {

class SimWorld;

struct SimRelayBoard {
  std::string port_path;              // "sim-1"
  std::string board_id;               // 5 characters at most
  int channels = 2;                   // 1, 2, 4 or 8
  std::map<int, std::string> lights;  // channel -> scene light it powers
};

class SimUsbRelayBus : public UsbRelayBus {
 public:
  explicit SimUsbRelayBus(std::shared_ptr<SimWorld> world = nullptr);

  // InvalidArgument for a duplicate port, a bad channel count or id.
  Status AddBoard(SimRelayBoard board);
  bool HasBoard(const std::string& board_id) const;
  // Wires `channel` of the board at `port_path` to scene light `light`.
  Status Wire(const std::string& port_path, int channel, const std::string& light);
  void Unplug(const std::string& port_path);
  void Replug(const std::string& port_path);
  void StickChannel(const std::string& port_path, int channel);
  uint8_t Mask(const std::string& port_path) const;

  Result<std::vector<Board>> List() override;
  Status SetReport(const std::string& port_path, const UsbRelayReport& report) override;
  Result<UsbRelayReport> GetReport(const std::string& port_path) override;

 private:
  struct State {
    SimRelayBoard board;
    uint8_t mask = 0;
    uint8_t stuck = 0;
    bool unplugged = false;
  };
  Result<State*> FindLocked(const std::string& port_path);
  void ApplyLightsLocked(const State& s);

  std::shared_ptr<SimWorld> world_;
  mutable std::mutex mutex_;
  std::map<std::string, State> boards_;
};

}  // namespace hairrig
