// Stopping a running capture from another thread: the operator console's stop
// and e-stop buttons, or a lab script through the console's API.
#pragma once

#include <functional>
#include <mutex>
#include <optional>
#include <string>

namespace hairrig {

class CaptureControl {
 public:
  enum class Kind {
    kStop,       // end after the stop being shot; frames in flight are stored
    kEmergency,  // as a safety input going active: turntable stopped at once, lights off
  };
  using Handler = std::function<void(Kind kind, const std::string& reason)>;

  // Either way the capture ends "stopped", journalled, and `--resume`
  // continues it. A request made before the capture runs (while its devices
  // open) takes effect as soon as it does; an emergency outranks a stop.
  void RequestStop(const std::string& reason) { Request(Kind::kStop, reason); }
  void EmergencyStop(const std::string& reason) { Request(Kind::kEmergency, reason); }

  // The sequencer's side: installs the running capture's handler (a request
  // already made is delivered at once) and removes it. After Detach returns
  // the handler is not running and is never called again.
  void Attach(Handler handler);
  void Detach();

 private:
  void Request(Kind kind, const std::string& reason);

  std::mutex mutex_;  // held while the handler runs
  Handler handler_;
  std::optional<Kind> pending_kind_;
  std::string pending_reason_;
};

}  // namespace hairrig
