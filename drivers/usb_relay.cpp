#include "drivers/usb_relay.h"

#include <libusb.h>

#include <cctype>
#include <mutex>

#include "core/config.h"

namespace hairrig {
namespace {

constexpr int kVendorId = 0x16c0;
constexpr int kProductId = 0x05df;
// HID class requests (HID 1.11, section 7.2) on interface 0, feature report 0.
constexpr uint8_t kSetReport = 0x09;
constexpr uint8_t kGetReport = 0x01;
constexpr uint16_t kFeatureReport0 = 0x0300;
constexpr unsigned kTimeoutMs = 1000;

std::string PortPath(libusb_device* device) {
  uint8_t ports[8];
  const int n = libusb_get_port_numbers(device, ports, sizeof(ports));
  std::string path = std::to_string(libusb_get_bus_number(device)) + "-";
  for (int i = 0; i < n; ++i) path += (i ? "." : "") + std::to_string(ports[i]);
  return path;
}

class LibusbRelayBus : public UsbRelayBus {
 public:
  ~LibusbRelayBus() override {
    if (context_ != nullptr) libusb_exit(context_);
  }

  Result<std::vector<Board>> List() override {
    std::lock_guard<std::mutex> lock(mutex_);
    HR_RETURN_IF_ERROR(Init());
    std::vector<Board> boards;
    ForEachRelay([&](libusb_device* device, libusb_device_handle* handle, uint8_t product_index) {
      unsigned char text[64] = {};
      if (handle &&
          libusb_get_string_descriptor_ascii(handle, product_index, text, sizeof(text)) > 0) {
        const std::string product = reinterpret_cast<const char*>(text);
        // 16c0:05df is V-USB's shared id: only boards naming themselves USBRelayN are relays.
        if (UsbRelayChannels(product) > 0) boards.push_back({PortPath(device), product});
      } else {
        boards.push_back({PortPath(device), ""});  // unreadable: listed, so that its error is seen
      }
      return false;
    });
    return boards;
  }

  Status SetReport(const std::string& port_path, const UsbRelayReport& report) override {
    UsbRelayReport copy = report;
    return Transfer(port_path, 0x21, kSetReport, &copy, "switching");
  }

  Result<UsbRelayReport> GetReport(const std::string& port_path) override {
    UsbRelayReport report{};
    HR_RETURN_IF_ERROR(Transfer(port_path, 0xA1, kGetReport, &report, "reading the state of"));
    return report;
  }

 private:
  Status Init() {
    if (context_ != nullptr) return Status::Ok();
    const int r = libusb_init(&context_);
    if (r != 0) {
      context_ = nullptr;
      return Unavailable(std::string("libusb cannot start: ") + libusb_error_name(r));
    }
    return Status::Ok();
  }

  // Calls `visit(device, handle or null, product string index)` for each
  // 16c0:05df device until it returns true.
  template <typename Visit>
  void ForEachRelay(Visit visit) {
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(context_, &list);
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device_descriptor d{};
      if (libusb_get_device_descriptor(list[i], &d) != 0 || d.idVendor != kVendorId ||
          d.idProduct != kProductId)
        continue;
      libusb_device_handle* handle = nullptr;
      if (libusb_open(list[i], &handle) != 0) handle = nullptr;
      const bool done = visit(list[i], handle, d.iProduct);
      if (handle) libusb_close(handle);
      if (done) break;
    }
    if (list) libusb_free_device_list(list, 1);
  }

  Status Transfer(const std::string& port_path, uint8_t type, uint8_t request,
                  UsbRelayReport* report, const char* what) {
    std::lock_guard<std::mutex> lock(mutex_);
    HR_RETURN_IF_ERROR(Init());
    Status result = Unavailable("no relay board at USB port " + port_path + " (unplugged?)");
    ForEachRelay([&](libusb_device* device, libusb_device_handle* handle, uint8_t) {
      if (PortPath(device) != port_path) return false;
      if (!handle) {
        result = Unavailable(
            "relay board at USB port " + port_path +
            " cannot be opened: add a udev rule giving the rig's user access to 16c0:05df");
        return true;
      }
      libusb_set_auto_detach_kernel_driver(handle, 1);
      int r = libusb_claim_interface(handle, 0);
      if (r == 0) {
        r = libusb_control_transfer(handle, type, request, kFeatureReport0, 0, report->data(),
                                    static_cast<uint16_t>(report->size()), kTimeoutMs);
        libusb_release_interface(handle, 0);
      }
      result = r >= 0 ? Status::Ok()
                      : Unavailable(std::string(what) + " the relay board at USB port " +
                                    port_path + ": " + libusb_error_name(r));
      return true;
    });
    return result;
  }

  std::mutex mutex_;
  libusb_context* context_ = nullptr;
};

class UsbRelayLight : public Light {
 public:
  UsbRelayLight(DeviceInfo info, UsbRelayLightOptions options)
      : Light(std::move(info)), options_(std::move(options)) {
    if (!options_.bus) options_.bus = MakeLibusbRelayBus();
  }
  ~UsbRelayLight() override { (void)UsbRelayLight::DoClose(); }

  LightCapabilities capabilities() const override { return {.dimmable = false}; }

 protected:
  Status DoOpen() override {
    port_path_.clear();
    auto boards = options_.bus->List();
    if (!boards.ok()) return Fault(boards.status());
    std::string seen;
    for (const UsbRelayBus::Board& b : *boards) {
      auto state = ReadState(b.port_path);
      if (!state.ok()) {
        seen += (seen.empty() ? "" : "; ") + b.port_path + ": " + state.status().message();
        continue;
      }
      if (state->board_id != options_.board_id) {
        seen +=
            (seen.empty() ? "" : "; ") + b.product + " '" + state->board_id + "' at " + b.port_path;
        continue;
      }
      const int channels = UsbRelayChannels(b.product);
      if (options_.channel > channels) {
        return Fault(OutOfRange("channel " + std::to_string(options_.channel) + ": the board (" +
                                b.product + ") has " + std::to_string(channels)));
      }
      port_path_ = b.port_path;
      SetState(DeviceState::kReady);
      return Status::Ok();
    }
    return Fault(
        Unavailable("no relay board with id '" + options_.board_id + "'" +
                    (seen.empty() ? std::string(" (none found)") : " (found: " + seen + ")") +
                    "; check its USB cable"));
  }

  Status DoClose() override {
    if (state() == DeviceState::kReady) (void)Switch(false);  // panels off when the program lets go
    return Status::Ok();
  }

  Status DoHealthCheck() override { return ReadState(port_path_).status(); }

  Status DoSetOn(bool on) override { return Switch(on); }

  Status DoSetLevel(double level) override {
    HR_ASSIGN_OR_RETURN(const bool on, OnOffFromLevel(*this, level, "a relay-switched panel"));
    return DoSetOn(on);
  }

  Result<bool> DoIsOn() override {
    HR_ASSIGN_OR_RETURN(UsbRelayState state, ReadState(port_path_));
    return state.IsOn(options_.channel);
  }

 private:
  Result<UsbRelayState> ReadState(const std::string& port_path) {
    auto report = options_.bus->GetReport(port_path);
    if (!report.ok()) return report.status();
    return DecodeUsbRelayState(*report);
  }

  // Switches the channel and checks that it followed.
  Status Switch(bool on) {
    HR_ASSIGN_OR_RETURN(const UsbRelayReport command, EncodeUsbRelaySwitch(options_.channel, on));
    Status s = options_.bus->SetReport(port_path_, command);
    if (!s.ok()) return Fault(s);
    auto state = ReadState(port_path_);
    if (!state.ok()) return Fault(state.status());
    if (state->IsOn(options_.channel) != on) {
      return Fault(DeviceFault("channel " + std::to_string(options_.channel) + " did not switch " +
                               (on ? "on" : "off") + " (the board reports mask 0x" +
                               std::to_string(state->on_mask) +
                               "); check the board's supply and the relay"));
    }
    return Status::Ok();
  }

  UsbRelayLightOptions options_;
  std::string port_path_;
};

}  // namespace

std::shared_ptr<UsbRelayBus> MakeLibusbRelayBus() { return std::make_shared<LibusbRelayBus>(); }

int UsbRelayChannels(const std::string& product) {
  const std::string prefix = "USBRelay";
  if (product.rfind(prefix, 0) != 0 || product.size() == prefix.size() ||
      product.size() > prefix.size() + 2)
    return 0;
  for (size_t i = prefix.size(); i < product.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(product[i]))) return 0;
  }
  const int channels = std::stoi(product.substr(prefix.size()));
  return channels >= 1 && channels <= kUsbRelayMaxChannels ? channels : 0;
}

Result<UsbRelayLightOptions> ParseUsbRelayLightOptions(
    const ConfigNode& device, const std::vector<std::string>& hook_fields) {
  std::vector<std::string> allowed{"name", "backend", "serial", "board", "channel", "bus"};
  allowed.insert(allowed.end(), hook_fields.begin(), hook_fields.end());
  device.AllowOnlyKeys(allowed);
  UsbRelayLightOptions o;
  o.board_id = device.String("board");
  if (o.board_id.size() > 5) device.Fail("board", "a relay board's id has at most 5 characters");
  o.channel = device.Integer("channel", {.min = 1, .max = kUsbRelayMaxChannels});
  o.bus_name = device.String("bus", kLibusbRelayBusName);
  if (!device.ok()) return device.status();
  return o;
}

Status UsbRelayLightOptions::Check() const {
  if (board_id.empty() || board_id.size() > 5) {
    return InvalidArgument("board must be a relay board's id of 1 to 5 characters, got " +
                           QuotedExcerpt(board_id));
  }
  if (channel < 1 || channel > kUsbRelayMaxChannels) {
    return InvalidArgument("channel must lie in 1.." + std::to_string(kUsbRelayMaxChannels) +
                           ", got " + std::to_string(channel));
  }
  if (bus_name.empty()) return InvalidArgument("bus must name a bus (usb)");
  return Status::Ok();
}

std::unique_ptr<Light> MakeUsbRelayLight(const DeviceInfo& info, UsbRelayLightOptions options) {
  return std::make_unique<UsbRelayLight>(info, std::move(options));
}

void RegisterUsbRelayBackend(DeviceRegistry* registry, UsbRelayOptionsHook hook,
                             std::vector<std::string> hook_fields) {
  registry->AddBackend<Light>(
      DeviceKind::kLight, "usbrelay",
      [hook, hook_fields](const DeviceConfig& c) -> Result<std::unique_ptr<Light>> {
        HR_ASSIGN_OR_RETURN(UsbRelayLightOptions options,
                            ParseUsbRelayLightOptions(c.node, hook_fields));
        if (hook) HR_RETURN_IF_ERROR(hook(c, &options));
        HR_RETURN_IF_ERROR(options.Check().WithContext("light " + c.name));
        if (options.bus_name != kLibusbRelayBusName && !options.bus) {
          return InvalidArgument(
              c.node.Where() + ": bus " + QuotedExcerpt(options.bus_name) +
              " is not a bus of this rig; use bus: usb (the boards on this machine's USB)");
        }
        return MakeUsbRelayLight(c.Info("USB relay board " + options.board_id + " channel " +
                                        std::to_string(options.channel)),
                                 std::move(options));
      });
}

}  // namespace hairrig
