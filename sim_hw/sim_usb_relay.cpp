#include "sim_hw/sim_usb_relay.h"

#include "sim_hw/sim_devices.h"

namespace hairrig {

SimUsbRelayBus::SimUsbRelayBus(std::shared_ptr<SimWorld> world) : world_(std::move(world)) {}

Status SimUsbRelayBus::AddBoard(SimRelayBoard board) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (boards_.count(board.port_path))
    return InvalidArgument("simulated relay: port " + board.port_path + " is taken");
  if (board.channels != 1 && board.channels != 2 && board.channels != 4 && board.channels != 8) {
    return InvalidArgument("simulated relay: boards have 1, 2, 4 or 8 channels, not " +
                           std::to_string(board.channels));
  }
  if (board.board_id.empty() || board.board_id.size() > 5) {
    return InvalidArgument("simulated relay: a board id has 1 to 5 characters: '" + board.board_id +
                           "'");
  }
  State s;
  s.board = std::move(board);
  boards_[s.board.port_path] = s;
  return Status::Ok();
}

bool SimUsbRelayBus::HasBoard(const std::string& board_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [port, s] : boards_) {
    if (s.board.board_id == board_id) return true;
  }
  return false;
}

Status SimUsbRelayBus::Wire(const std::string& port_path, int channel, const std::string& light) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = boards_.find(port_path);
  if (it == boards_.end()) return NotFound("simulated relay: no board at " + port_path);
  if (channel < 1 || channel > it->second.board.channels) {
    return OutOfRange("simulated relay " + it->second.board.board_id + ": no channel " +
                      std::to_string(channel));
  }
  it->second.board.lights[channel] = light;
  return Status::Ok();
}

void SimUsbRelayBus::Unplug(const std::string& port_path) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = boards_.find(port_path); it != boards_.end()) it->second.unplugged = true;
}

void SimUsbRelayBus::Replug(const std::string& port_path) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = boards_.find(port_path); it != boards_.end()) {
    it->second.unplugged = false;
    it->second.mask = it->second.stuck & it->second.mask;  // a board powers up with its relays off
  }
}

void SimUsbRelayBus::StickChannel(const std::string& port_path, int channel) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = boards_.find(port_path); it != boards_.end())
    it->second.stuck |= static_cast<uint8_t>(1u << (channel - 1));
}

uint8_t SimUsbRelayBus::Mask(const std::string& port_path) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = boards_.find(port_path);
  return it == boards_.end() ? 0 : it->second.mask;
}

Result<std::vector<UsbRelayBus::Board>> SimUsbRelayBus::List() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Board> out;
  for (const auto& [port, s] : boards_) {
    if (!s.unplugged) out.push_back({port, "USBRelay" + std::to_string(s.board.channels)});
  }
  return out;
}

Result<SimUsbRelayBus::State*> SimUsbRelayBus::FindLocked(const std::string& port_path) {
  auto it = boards_.find(port_path);
  if (it == boards_.end() || it->second.unplugged) {
    return Unavailable("no relay board at USB port " + port_path + " (unplugged?)");
  }
  return &it->second;
}

Status SimUsbRelayBus::SetReport(const std::string& port_path, const UsbRelayReport& report) {
  std::lock_guard<std::mutex> lock(mutex_);
  HR_ASSIGN_OR_RETURN(State * s, FindLocked(port_path));
  const uint8_t all = static_cast<uint8_t>((1u << s->board.channels) - 1);
  const int channel = report[1];
  const bool addressed = channel >= 1 && channel <= s->board.channels;
  const uint8_t bit = static_cast<uint8_t>(addressed ? 1u << (channel - 1) : 0u);
  uint8_t wanted = s->mask;
  switch (report[0]) {
    case 0xFF:
      wanted |= bit;
      break;
    case 0xFD:
      wanted &= static_cast<uint8_t>(~bit);
      break;
    case 0xFE:
      wanted = all;
      break;
    case 0xFC:
      wanted = 0;
      break;
    default:
      return Status::Ok();  // the firmware ignores what it does not know
  }
  s->mask = static_cast<uint8_t>((wanted & ~s->stuck) | (s->mask & s->stuck));
  ApplyLightsLocked(*s);
  return Status::Ok();
}

Result<UsbRelayReport> SimUsbRelayBus::GetReport(const std::string& port_path) {
  std::lock_guard<std::mutex> lock(mutex_);
  HR_ASSIGN_OR_RETURN(State * s, FindLocked(port_path));
  UsbRelayReport report{};
  for (size_t i = 0; i < s->board.board_id.size(); ++i)
    report[i] = static_cast<uint8_t>(s->board.board_id[i]);
  report[7] = s->mask;
  return report;
}

void SimUsbRelayBus::ApplyLightsLocked(const State& s) {
  if (!world_) return;
  for (const auto& [channel, light] : s.board.lights) {
    (void)SetWorldLightLevel(*world_, light, (s.mask >> (channel - 1)) & 1 ? 1.0 : 0.0);
  }
}

}  // namespace hairrig
