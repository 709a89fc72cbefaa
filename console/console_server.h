// `hairrig serve`: the operator console (docs/design.md section 9). One process
// owns the rig's devices (console/console_rig.h) and serves the page
// (console/web/, built into the binary) and a JSON API with live events
// (Server-Sent Events), documented in docs/console-api.md.
//
// Security: it listens on 127.0.0.1 unless told otherwise, and beyond
// loopback only with a token, which every API request must carry
// ("Authorization: Bearer T" or "?token=T"). On loopback the Host header must
// name loopback (no DNS rebinding). Requests that change anything are POST or
// DELETE with a JSON body ("Content-Type: application/json", which a page of
// another site cannot send without the CORS preflight this server never
// grants); those that move or light the rig also need the control lease
// (console/control_lease.h) except the e-stop, which any client may press.
// Captures are addressed by id, never by a client's path.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "console/console_rig.h"
#include "console/http_server.h"
#include "core/status.h"

namespace hairrig {

struct ConsoleOptions {
  ConsoleRigOptions rig;
  std::string listen = "127.0.0.1:8080";  // host:port; port 0 picks a free one
  // Required when the host is not a loopback address; at least 16 characters.
  std::string token;
  std::chrono::milliseconds lease_ttl{
      15000};                  // control lapses this long after its holder's last word
  int max_event_streams = 16;  // concurrent GET /api/events
  // Connection bounds and timeouts of the HTTP server (console/http_server.h).
  HttpServerOptions http;

  // InvalidArgument naming the field: a malformed listen address, a
  // non-loopback host without a token (or a short one), a lease_ttl that is
  // not positive, max_event_streams below 1, the rig's (rig.*) or the HTTP
  // server's (http: ...) options.
  Status Check() const;
};

// True for 127.0.0.0/8, ::1 and "localhost".
bool IsLoopbackHost(const std::string& host);

class ConsoleServer {
 public:
  explicit ConsoleServer(ConsoleOptions options);
  ~ConsoleServer();
  ConsoleServer(const ConsoleServer&) = delete;
  ConsoleServer& operator=(const ConsoleServer&) = delete;

  // Starts the rig (ConsoleRig::Start) and listens; returns once requests are
  // served. Errors: the options, the rig's, an address that cannot be bound.
  Status Start();
  // Stops serving; a running capture is stopped (resumable) and the devices closed.
  void Stop();
  int port() const { return port_; }
  std::string url() const;  // "http://127.0.0.1:8080/"

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
  int port_ = 0;
  std::string host_;
};

struct ConsoleSummary {
  std::string url;
  double served_s = 0;
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// `hairrig serve`: runs a ConsoleServer until `stop` becomes true (polled
// every 100 ms; the command line sets it on SIGINT or SIGTERM). `on_listening`
// is told the URL once requests are served.
Result<ConsoleSummary> RunConsole(const ConsoleOptions& options, const std::atomic<bool>& stop,
                                  const std::function<void(const std::string& url)>& on_listening);

}  // namespace hairrig
