// `hairrig estop`: presses a running console's e-stop from a terminal.
//
//   EStopRequest request;             // url "http://127.0.0.1:8080/" by default
//   Result<EStopSummary> pressed = PressConsoleEStop(request);
//
// It sends POST /api/estop (console/console_server.h), which the console
// serves on a thread of its own ahead of every other request; the answer
// comes after the rig has acted (turntable stopped, lights off, a running
// capture stopped, resumable). This is a software path like the page's
// button: the e-stop to rely on is the hardware one (docs/hardware.md).
#pragma once

#include <chrono>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/status.h"

namespace hairrig {

struct EStopRequest {
  std::string url = "http://127.0.0.1:8080/";  // the console, as `hairrig serve` prints it
  std::string token;                           // required beyond loopback
  std::string who = "the command line";        // recorded as the e-stop's reason
  std::chrono::milliseconds timeout{3000};     // for connecting and for the answer

  // InvalidArgument naming the field: a URL that is not http://host:port/, a
  // timeout that is not positive.
  Status Check() const;
};

struct EStopSummary {
  std::string url;
  bool active = false;  // the console reports the e-stop active
  std::string reason;
  double seconds = 0;  // from connecting to the answer
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Unavailable naming the URL when the console does not answer within the
// timeout (then use the rig's hardware e-stop); the console's own error
// (a missing token, say) otherwise.
Result<EStopSummary> PressConsoleEStop(const EStopRequest& request);

}  // namespace hairrig
