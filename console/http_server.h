// A small HTTP/1.1 server built so that a flood of connections cannot starve
// one request: the operator console's e-stop must be acted on whatever the
// other connections do.
//
//   HttpServer server(HttpServerOptions{});
//   server.Route("GET", "/api/state", [](const HttpRequest&, HttpResponse& res) {...});
//   server.Route("POST", "/api/estop", handler, HttpLane::kUrgent);
//   HR_RETURN_IF_ERROR(server.Listen("127.0.0.1", 0));   // port() is then bound
//   ...
//   server.Stop();
//
// How it holds under load:
// - One event-loop thread (epoll) accepts every connection and reads requests
//   without blocking; a connection costs memory, not a thread, until its
//   request is complete. The loop sleeps in epoll_wait between events (with a
//   100 ms tick for the timeouts): idle connections cost no CPU.
// - A request must be complete (headers and body) within request_timeout of
//   its first byte, and a connection that sends nothing is closed after
//   idle_timeout: slow-header clients are dropped.
// - Connections are bounded per client address and in all. A new connection
//   over a bound closes the oldest connection still waiting for its request
//   (never one whose request is being served), so the newest connection, such
//   as an e-stop just sent, is always read.
// - The loop parses, screens (SetScreen) and routes each complete request;
//   refusals and unknown paths are answered there. The rest go to a lane:
//   kUrgent routes have their own thread and queue, so a busy worker pool
//   never delays them; kNormal routes share a pool of workers. Lanes never
//   touch a socket: the loop writes every response without blocking, within
//   write_timeout plus a second per 64 KiB, so a client that does not read
//   holds nothing but its own connection. A connection's next request is read
//   once its response is written.
// - A response with a stream (Server-Sent Events) gets a thread of its own
//   for its life, up to max_streams at once; it writes with a bound per write.
// - Accepted sockets are moved above FD_SETSIZE + 64, so that the process's
//   low descriptors stay free for libraries that call select() (libmodbus).
//
// Refused with an error: a request target above 2 KiB (414), a Content-Length
// given twice or malformed (400), any Transfer-Encoding (411), bodies above
// max_body_bytes (413), headers above max_header_bytes (431), header names
// that are not tokens or values with control characters (400). Paths are
// percent-decoded before matching.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/status.h"

namespace hairrig {

struct HttpServerOptions {
  // Connections open at once, in all and from one client address. Over a
  // bound, the oldest connection still waiting for its request is closed.
  // Listen raises the open-file limit to fit max_connections where the hard
  // limit allows; where it does not, a connection refused for want of a file
  // descriptor also closes the oldest waiting one.
  int max_connections = 8192;
  int max_connections_per_client = 4096;
  // A request (headers and body) must be complete this long after its first byte.
  std::chrono::milliseconds request_timeout{5000};
  // A connection that has sent nothing (new, or idle between requests) is closed after this.
  std::chrono::milliseconds idle_timeout{30000};
  // A response must be taken by the client within this (per blocking write).
  std::chrono::milliseconds write_timeout{5000};
  int normal_workers = 8;  // threads for kNormal routes
  int max_streams = 32;    // streaming responses at once; more are answered 503
  size_t max_header_bytes = 16 * 1024;
  size_t max_body_bytes = 1 << 20;
  int listen_backlog = 4096;  // the kernel caps it at net.core.somaxconn

  // InvalidArgument naming the field for a bound below 1 or a zero timeout.
  Status Check() const;
};

struct HttpRequest {
  std::string method;                                        // "GET", "POST", ...
  std::string path;                                          // percent-decoded, without the query
  std::string query;                                         // raw, without '?'
  std::string remote_addr;                                   // "127.0.0.1" or "::1"
  std::vector<std::pair<std::string, std::string>> headers;  // names in lower case
  std::string body;
  std::vector<std::string> matches;  // [0] the whole path, then the pattern's groups

  // The header's value ("" when absent); the name is matched case-insensitively.
  std::string Header(const std::string& name) const;
  // The query parameter's decoded value ("" when absent).
  std::string Param(const std::string& name) const;
};

// Given to a stream's writer; Write returns false once the client is gone.
class HttpStreamSink {
 public:
  virtual ~HttpStreamSink() = default;
  virtual bool Write(const std::string& data) = 0;
};

struct HttpResponse {
  int status = 200;
  std::vector<std::pair<std::string, std::string>> headers;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  // When set, the body is streamed (chunked) instead: `stream` is called
  // again and again on the response's own thread until it returns false or
  // the client is gone; `on_stream_end` is called once after, on that thread.
  std::function<bool(HttpStreamSink&)> stream;
  std::function<void()> on_stream_end;

  void SetHeader(const std::string& name, const std::string& value);
  void SetContent(std::string content, const std::string& type);
  void SetContent(const void* data, size_t size, const std::string& type);
};

enum class HttpLane {
  kNormal,  // the shared worker pool
  kUrgent,  // a thread of its own: never waits behind kNormal requests
};

struct HttpServerStats {
  uint64_t accepted = 0;
  uint64_t requests = 0;
  uint64_t closed_idle = 0;     // sent nothing within idle_timeout
  uint64_t closed_slow = 0;     // request not complete within request_timeout, or response
                                // not taken within its time
  uint64_t closed_evicted = 0;  // closed for a newer connection over a bound
  uint64_t refused_streams = 0;
  int open_connections = 0;
};

class HttpServer {
 public:
  using Handler = std::function<void(const HttpRequest&, HttpResponse&)>;
  // Runs on the event loop before routing, so it must be quick and must not
  // block; returns true when it has answered the request itself (refused it).
  using Screen = std::function<bool(const HttpRequest&, HttpResponse&)>;

  explicit HttpServer(HttpServerOptions options);
  ~HttpServer();  // Stop()
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // `pattern` is an ECMAScript regex matched against the whole decoded path.
  // Routes are tried in the order given; call before Listen.
  void Route(const std::string& method, const std::string& pattern, Handler handler,
             HttpLane lane = HttpLane::kNormal);
  void SetScreen(Screen screen);

  // Binds host:port (port 0 picks a free one), raises the process's
  // open-file limit to what the connection bounds need (up to the hard
  // limit), and starts serving. Unavailable naming the address when it cannot bind.
  Status Listen(const std::string& host, int port);
  int port() const;
  // Stops accepting, ends streams (their writers see the client gone once
  // they return) and joins every thread. Safe to call twice.
  void Stop();
  HttpServerStats Stats() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
