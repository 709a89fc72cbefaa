#include "console/http_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <list>
#include <map>
#include <mutex>
#include <regex>
#include <thread>
#include <unordered_map>

#include "core/log.h"

namespace hairrig {

namespace {

using Clock = std::chrono::steady_clock;

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Percent-decoding ('+' as a space where `plus_is_space`); false on a
// malformed escape or a decoded NUL.
bool PercentDecode(const std::string& in, bool plus_is_space, std::string* out) {
  out->clear();
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] == '%') {
      if (i + 2 >= in.size()) return false;
      const int hi = HexDigit(in[i + 1]), lo = HexDigit(in[i + 2]);
      if (hi < 0 || lo < 0 || (hi == 0 && lo == 0)) return false;
      out->push_back(static_cast<char>(hi * 16 + lo));
      i += 2;
    } else {
      out->push_back(plus_is_space && in[i] == '+' ? ' ' : in[i]);
    }
  }
  return true;
}

const char* ReasonPhrase(int status) {
  switch (status) {
    case 200:
      return "OK";
    case 201:
      return "Created";
    case 202:
      return "Accepted";
    case 204:
      return "No Content";
    case 400:
      return "Bad Request";
    case 401:
      return "Unauthorized";
    case 403:
      return "Forbidden";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 409:
      return "Conflict";
    case 411:
      return "Length Required";
    case 413:
      return "Content Too Large";
    case 414:
      return "URI Too Long";
    case 415:
      return "Unsupported Media Type";
    case 431:
      return "Request Header Fields Too Large";
    case 500:
      return "Internal Server Error";
    case 503:
      return "Service Unavailable";
    default:
      return "Status";
  }
}

// How a response's body is framed.
enum class Framing { kLength, kChunked, kUntilClose };

std::string StatusLineAndHeaders(const HttpResponse& res, bool keep_alive, Framing framing) {
  std::string head = "HTTP/1.1 " + std::to_string(res.status) + " " + ReasonPhrase(res.status) +
                     "\r\nContent-Type: " + res.content_type + "\r\n";
  for (const auto& [name, value] : res.headers) head += name + ": " + value + "\r\n";
  if (framing == Framing::kChunked) head += "Transfer-Encoding: chunked\r\n";
  if (framing == Framing::kLength)
    head += "Content-Length: " + std::to_string(res.body.size()) + "\r\n";
  head += keep_alive ? "Connection: keep-alive\r\n\r\n" : "Connection: close\r\n\r\n";
  return head;
}

// A whole response with a Content-Length.
std::string ResponseText(const HttpResponse& res, bool keep_alive) {
  return StatusLineAndHeaders(res, keep_alive, Framing::kLength) + res.body;
}

HttpResponse JsonError(int status, const std::string& message) {
  HttpResponse res;
  res.status = status;
  res.SetContent("{\"error\":\"" + message + "\"}", "application/json");
  return res;
}

// Writes all of `data` to the non-blocking socket, waiting for room up to
// `timeout` each time the socket is full. False when the client is gone or
// slow. Only stream threads write this way; every other response is written
// by the event loop without blocking.
bool WriteAll(int fd, const char* data, size_t size, std::chrono::milliseconds timeout) {
  while (size > 0) {
    const ssize_t n = ::send(fd, data, size, MSG_NOSIGNAL);
    if (n > 0) {
      data += n;
      size -= static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd, POLLOUT, 0};
      if (::poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return false;
      if (p.revents & (POLLERR | POLLHUP)) return false;
      continue;
    }
    return false;
  }
  return true;
}

std::string PeerAddress(const sockaddr_storage& addr) {
  char text[INET6_ADDRSTRLEN] = {};
  if (addr.ss_family == AF_INET) {
    inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in&>(addr).sin_addr, text, sizeof text);
  } else if (addr.ss_family == AF_INET6) {
    inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6&>(addr).sin6_addr, text, sizeof text);
  }
  return text;
}

// Accepted connections are moved to descriptors from here up, so that the
// low ones stay free for the rest of the process: libraries that call
// select() (libmodbus) abort on a descriptor at or above FD_SETSIZE.
constexpr int kFirstConnectionFd = FD_SETSIZE + 64;

// Raises the soft open-file limit to `wanted` (at most the hard limit) and
// returns the limit in force.
rlim_t RaiseOpenFileLimit(rlim_t wanted) {
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0) return 1024;
  if (limit.rlim_cur >= wanted) return limit.rlim_cur;
  limit.rlim_cur = std::min(wanted, limit.rlim_max);
  if (setrlimit(RLIMIT_NOFILE, &limit) != 0) {
    LogWarning("http: cannot raise the open-file limit: " + std::string(std::strerror(errno)));
    getrlimit(RLIMIT_NOFILE, &limit);
  }
  return limit.rlim_cur;
}

// How many connections fit under the open-file limit `limit`, beside the
// descriptors the rest of the process needs.
int ConnectionsThatFit(rlim_t limit, int wanted, int streams) {
  const int64_t room = static_cast<int64_t>(limit) > kFirstConnectionFd + 256
                           ? static_cast<int64_t>(limit) - kFirstConnectionFd - 64 - streams
                           : static_cast<int64_t>(limit) / 2;
  return static_cast<int>(std::clamp<int64_t>(room, 1, wanted));
}

bool IsTokenChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) ||
         std::strchr("!#$%&'*+-.^_`|~", c) != nullptr;
}

// What a request's head (request line and headers, without the blank line) says.
struct RequestHead {
  int refuse_status = 0;  // non-zero: answer this and close
  std::string refuse_message;
  HttpRequest request;  // method, path, query, headers
  size_t body_size = 0;
  bool http11 = true;
};

RequestHead Refused(int status, const std::string& message) {
  RequestHead head;
  head.refuse_status = status;
  head.refuse_message = message;
  return head;
}

// Parses the request line; the target is at most `max_target` bytes.
RequestHead ParseRequestLine(const std::string& line, size_t max_target) {
  const size_t sp1 = line.find(' ');
  const size_t sp2 = line.rfind(' ');
  if (sp1 == std::string::npos || sp2 == sp1) return Refused(400, "malformed request line");
  RequestHead head;
  HttpRequest& req = head.request;
  req.method = line.substr(0, sp1);
  const std::string target = line.substr(sp1 + 1, sp2 - sp1 - 1);
  const std::string version = line.substr(sp2 + 1);
  if (version != "HTTP/1.1" && version != "HTTP/1.0")
    return Refused(400, "expected HTTP/1.0 or HTTP/1.1");
  head.http11 = version == "HTTP/1.1";
  if (req.method.empty() || !std::all_of(req.method.begin(), req.method.end(), IsTokenChar))
    return Refused(400, "malformed method");
  if (target.size() > max_target) return Refused(414, "request target too long");
  const size_t question = target.find('?');
  if (!PercentDecode(target.substr(0, question), false, &req.path) || req.path.empty() ||
      req.path.front() != '/')
    return Refused(400, "malformed path");
  if (question != std::string::npos) req.query = target.substr(question + 1);
  return head;
}

// Adds one header line; false when it is malformed (no folding, a token
// name, no control characters in the value).
bool AddHeaderLine(const std::string& line, HttpRequest* req) {
  const size_t colon = line.find(':');
  if (colon == std::string::npos || colon == 0) return false;
  const std::string name = line.substr(0, colon);
  if (!std::all_of(name.begin(), name.end(), IsTokenChar)) return false;
  for (size_t i = colon + 1; i < line.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(line[i]);
    if ((c < 0x20 && c != '\t') || c == 0x7f) return false;
  }
  const size_t value_start = line.find_first_not_of(" \t", colon + 1);
  const size_t value_end = line.find_last_not_of(" \t");
  req->headers.emplace_back(Lower(name),
                            value_start == std::string::npos
                                ? ""
                                : line.substr(value_start, value_end - value_start + 1));
  return true;
}

// The body's size from the headers: one Content-Length at most, and no
// Transfer-Encoding (which this server does not take).
RequestHead BodySize(RequestHead head, size_t max_body) {
  int lengths = 0;
  for (const auto& [name, value] : head.request.headers) {
    if (name == "transfer-encoding")
      return Refused(411, "send the body with Content-Length, not a transfer encoding");
    if (name != "content-length") continue;
    if (++lengths > 1) return Refused(400, "more than one Content-Length");
    if (value.empty() || value.size() > 12 ||
        value.find_first_not_of("0123456789") != std::string::npos)
      return Refused(400, "malformed Content-Length");
    head.body_size = std::stoull(value);
  }
  if (head.body_size > max_body) return Refused(413, "request body too large");
  return head;
}

RequestHead ParseRequestHead(const std::string& text, size_t max_target, size_t max_body) {
  size_t line_end = text.find("\r\n");
  RequestHead head = ParseRequestLine(text.substr(0, line_end), max_target);
  if (head.refuse_status) return head;
  while (line_end != std::string::npos && line_end < text.size()) {
    const size_t start = line_end + 2;
    line_end = text.find("\r\n", start);
    if (!AddHeaderLine(text.substr(start, line_end - start), &head.request))
      return Refused(400, "malformed header line");
  }
  return BodySize(std::move(head), max_body);
}

}  // namespace

Status HttpServerOptions::Check() const {
  if (max_connections < 1) return InvalidArgument("http: max_connections must be at least 1");
  if (max_connections_per_client < 1 || max_connections_per_client > max_connections)
    return InvalidArgument("http: max_connections_per_client must be in [1, max_connections]");
  if (request_timeout.count() <= 0 || idle_timeout.count() <= 0 || write_timeout.count() <= 0)
    return InvalidArgument(
        "http: request_timeout, idle_timeout and write_timeout must be positive");
  if (normal_workers < 1) return InvalidArgument("http: normal_workers must be at least 1");
  if (max_streams < 0) return InvalidArgument("http: max_streams must not be negative");
  if (max_header_bytes < 256) return InvalidArgument("http: max_header_bytes below 256");
  if (listen_backlog < 1) return InvalidArgument("http: listen_backlog must be at least 1");
  return Status::Ok();
}

std::string HttpRequest::Header(const std::string& name) const {
  const std::string key = Lower(name);
  for (const auto& [n, v] : headers) {
    if (n == key) return v;
  }
  return "";
}

std::string HttpRequest::Param(const std::string& name) const {
  size_t start = 0;
  while (start <= query.size()) {
    size_t end = query.find('&', start);
    if (end == std::string::npos) end = query.size();
    const std::string pair = query.substr(start, end - start);
    const size_t eq = pair.find('=');
    std::string key, value;
    if (PercentDecode(pair.substr(0, eq), true, &key) && key == name) {
      if (eq == std::string::npos) return "";
      return PercentDecode(pair.substr(eq + 1), true, &value) ? value : "";
    }
    start = end + 1;
  }
  return "";
}

void HttpResponse::SetHeader(const std::string& name, const std::string& value) {
  for (auto& [n, v] : headers) {
    if (Lower(n) == Lower(name)) {
      v = value;
      return;
    }
  }
  headers.emplace_back(name, value);
}

void HttpResponse::SetContent(std::string content, const std::string& type) {
  body = std::move(content);
  content_type = type;
}

void HttpResponse::SetContent(const void* data, size_t size, const std::string& type) {
  body.assign(static_cast<const char*>(data), size);
  content_type = type;
}

// ---------------------------------------------------------------------------

class HttpServer::Impl {
 public:
  explicit Impl(HttpServerOptions options) : options_(std::move(options)) {}
  ~Impl() { Stop(); }

  void AddRoute(const std::string& method, const std::string& pattern, Handler handler,
                HttpLane lane) {
    routes_.push_back({method, std::regex(pattern), std::move(handler), lane});
  }
  void SetScreen(Screen screen) { screen_ = std::move(screen); }
  Status Listen(const std::string& host, int port);
  int port() const { return port_; }
  void Stop();
  HttpServerStats Stats() const;

 private:
  enum class ConnState {
    kReading,  // waiting for (the rest of) a request
    kBusy,     // its request is on a lane, or its stream thread owns it
    kWriting,  // the loop is writing its response
    kClosing,  // answered and shut down for writing; drained until the client closes
  };
  struct Connection {
    int fd = -1;
    std::string remote_addr;
    std::string in;      // bytes read and not yet consumed by a request
    size_t scanned = 0;  // bytes of `in` searched for the end of the head
    std::string out;     // the response being written
    size_t out_sent = 0;
    bool close_after_write = false;
    Clock::time_point last_activity;  // the last byte read or written
    Clock::time_point first_byte;     // of the request being read
    Clock::time_point out_deadline;   // the whole response written by then
    ConnState state = ConnState::kReading;
    bool watched = false;  // registered with epoll
    bool sent_continue = false;
    bool peer_closed = false;  // the client shut down its side: answer what it sent, then close
  };
  struct RouteEntry {
    std::string method;
    std::regex pattern;
    Handler handler;
    HttpLane lane;
  };
  struct Job {
    Connection* conn = nullptr;
    HttpRequest request;
    const RouteEntry* route = nullptr;
    bool keep_alive = true;
    bool http11 = true;
  };
  // A queue served by its own threads.
  struct Lane {
    std::mutex mutex;
    std::condition_variable ready;
    std::deque<Job> jobs;
    std::vector<std::thread> threads;
  };
  struct StreamThread {
    std::thread thread;
    std::atomic<bool> done{false};
  };
  // A response handed back to the loop by a lane or a stream thread.
  struct Returned {
    Connection* conn;
    std::string out;  // empty: nothing more to write (a stream ended)
    bool keep_alive;
  };
  enum class Dispatch { kDispatched, kIncomplete, kClosed };

  Status OpenSockets(const std::string& host, int port);
  void LoopMain();
  void OnEvent(int fd, uint32_t events);
  void AcceptSome();
  void MakeRoom(const std::string& remote_addr);
  bool EvictOne(const std::string* client);
  bool Drain(Connection* conn);
  void ReadFrom(Connection* conn);
  Dispatch TryDispatch(Connection* conn);
  Dispatch Route(Connection* conn, RequestHead head);
  void Respond(Connection* conn, std::string text, bool keep_alive);
  void Flush(Connection* conn);
  void AfterResponse(Connection* conn);
  void Refuse(Connection* conn, int status, const std::string& message);
  void Close(Connection* conn);
  void SweepTimeouts();
  void TakeBackReturned();
  void Watch(Connection* conn, uint32_t events);
  void Unwatch(Connection* conn);
  void WorkerMain(Lane* lane);
  void Serve(Job job);
  void StartStream(Job job, HttpResponse response);
  void StreamMain(Connection* conn, const HttpResponse& res, bool http11);
  void ReturnToLoop(Connection* conn, std::string out, bool keep_alive);
  void Wake();
  void Count(uint64_t HttpServerStats::*field, uint64_t n = 1);

  const HttpServerOptions options_;
  int max_connections_ = 0;  // options_.max_connections, or what fits under the open-file limit
  std::vector<RouteEntry> routes_;
  Screen screen_;
  int port_ = 0;
  int listen_fd_ = -1;
  int epoll_fd_ = -1;
  int wake_fd_ = -1;
  bool listen_paused_ = false;
  std::atomic<bool> stopping_{false};
  std::thread loop_;
  Lane urgent_, normal_;

  // Owned by the loop thread, busy connections included (their descriptors
  // are closed only by the loop, or by Stop once the loop has ended).
  std::unordered_map<int, std::unique_ptr<Connection>> connections_;
  std::map<std::string, int> per_client_;
  std::atomic<int> open_connections_{0};
  Clock::time_point last_sweep_;

  std::mutex returned_mutex_;
  std::vector<Returned> returned_;

  std::mutex streams_mutex_;
  std::list<std::unique_ptr<StreamThread>> streams_;

  mutable std::mutex stats_mutex_;
  HttpServerStats stats_;
};

void HttpServer::Impl::Count(uint64_t HttpServerStats::*field, uint64_t n) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.*field += n;
}

Status HttpServer::Impl::OpenSockets(const std::string& host, int port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  const std::string where = host + ":" + service;
  if (getaddrinfo(host.c_str(), service.c_str(), &hints, &found) != 0 || !found)
    return Unavailable("listen: cannot resolve '" + host + "'");
  std::unique_ptr<addrinfo, decltype(&freeaddrinfo)> addresses(found, freeaddrinfo);
  listen_fd_ = ::socket(found->ai_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) return Unavailable("listen: socket: " + std::string(std::strerror(errno)));
  const int one = 1;
  setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(listen_fd_, found->ai_addr, found->ai_addrlen) != 0 ||
      ::listen(listen_fd_, options_.listen_backlog) != 0)
    return Unavailable("listen: cannot bind " + where + " (" + std::strerror(errno) +
                       "; in use? another console running?)");
  sockaddr_storage bound{};
  socklen_t length = sizeof bound;
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&bound), &length);
  port_ = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6&>(bound).sin6_port
                                            : reinterpret_cast<sockaddr_in&>(bound).sin_port);
  epoll_fd_ = epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  epoll_event listen_event{EPOLLIN, {.fd = listen_fd_}};
  epoll_event wake_event{EPOLLIN, {.fd = wake_fd_}};
  if (epoll_fd_ < 0 || wake_fd_ < 0 ||
      epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, listen_fd_, &listen_event) != 0 ||
      epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &wake_event) != 0)
    return Unavailable("listen: cannot set up epoll: " + std::string(std::strerror(errno)));
  return Status::Ok();
}

Status HttpServer::Impl::Listen(const std::string& host, int port) {
  HR_RETURN_IF_ERROR(options_.Check());
  if (const Status opened = OpenSockets(host, port); !opened.ok()) {
    Stop();
    return opened;
  }
  const rlim_t wanted = static_cast<rlim_t>(kFirstConnectionFd + options_.max_connections +
                                            options_.max_streams + 64);
  max_connections_ = ConnectionsThatFit(RaiseOpenFileLimit(wanted), options_.max_connections,
                                        options_.max_streams);
  if (max_connections_ < options_.max_connections)
    LogWarning("http: the open-file limit allows " + std::to_string(max_connections_) +
               " connections, not " + std::to_string(options_.max_connections) +
               " (raise it with ulimit -n)");
  urgent_.threads.emplace_back([this] { WorkerMain(&urgent_); });
  for (int i = 0; i < options_.normal_workers; ++i)
    normal_.threads.emplace_back([this] { WorkerMain(&normal_); });
  last_sweep_ = Clock::now();
  loop_ = std::thread([this] { LoopMain(); });
  return Status::Ok();
}

void HttpServer::Impl::Wake() {
  const uint64_t one = 1;
  (void)!::write(wake_fd_, &one, sizeof one);
}

void HttpServer::Impl::LoopMain() {
  std::vector<epoll_event> events(256);
  while (!stopping_.load()) {
    const int n = epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()), 100);
    for (int i = 0; i < n; ++i) OnEvent(events[i].data.fd, events[i].events);
    TakeBackReturned();
    if (Clock::now() - last_sweep_ >= std::chrono::milliseconds(100)) SweepTimeouts();
  }
}

void HttpServer::Impl::OnEvent(int fd, uint32_t events) {
  if (fd == listen_fd_) return AcceptSome();
  if (fd == wake_fd_) {
    uint64_t count = 0;
    (void)!::read(wake_fd_, &count, sizeof count);
    return;
  }
  const auto it = connections_.find(fd);
  if (it == connections_.end()) return;
  Connection* conn = it->second.get();
  if (conn->state == ConnState::kWriting) {
    if (events & (EPOLLERR | EPOLLHUP)) return Close(conn);
    return Flush(conn);
  }
  if (conn->state == ConnState::kClosing) {
    if (!Drain(conn)) Close(conn);
    return;
  }
  if (conn->state == ConnState::kReading) ReadFrom(conn);
}

// Accepts at most a batch per wake, so that the requests of connections
// already accepted are read between batches.
void HttpServer::Impl::AcceptSome() {
  for (int batch = 0; batch < 64; ++batch) {
    sockaddr_storage addr{};
    socklen_t length = sizeof addr;
    int fd = accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &length,
                     SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if ((errno == EMFILE || errno == ENFILE) && EvictOne(nullptr)) continue;
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        // Nothing to give up: stop listening until the next tick.
        epoll_event paused{0, {.fd = listen_fd_}};
        epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, listen_fd_, &paused);
        listen_paused_ = true;
      }
      return;
    }
    if (const int high = fcntl(fd, F_DUPFD_CLOEXEC, kFirstConnectionFd); high >= 0) {
      ::close(fd);
      fd = high;
    }
    const int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    auto conn = std::make_unique<Connection>();
    conn->fd = fd;
    conn->remote_addr = PeerAddress(addr);
    conn->last_activity = Clock::now();
    MakeRoom(conn->remote_addr);
    ++per_client_[conn->remote_addr];
    Connection* raw = conn.get();
    connections_[fd] = std::move(conn);
    ++open_connections_;
    Watch(raw, EPOLLIN | EPOLLRDHUP);
    Count(&HttpServerStats::accepted);
  }
}

void HttpServer::Impl::MakeRoom(const std::string& remote_addr) {
  const auto it = per_client_.find(remote_addr);
  if (it != per_client_.end() && it->second >= options_.max_connections_per_client)
    EvictOne(&remote_addr);
  if (static_cast<int>(connections_.size()) >= max_connections_) EvictOne(nullptr);
}

// Closes the connection that has waited longest without progress (of
// `client`, or of anyone). A candidate whose complete request has arrived
// meanwhile is dispatched instead, and the next one is tried.
bool HttpServer::Impl::EvictOne(const std::string* client) {
  std::vector<Connection*> candidates;
  for (const auto& [fd, conn] : connections_) {
    if (conn->state != ConnState::kReading && conn->state != ConnState::kClosing) continue;
    if (client && conn->remote_addr != *client) continue;
    candidates.push_back(conn.get());
  }
  const size_t tries = std::min<size_t>(candidates.size(), 8);
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<long>(tries),
                    candidates.end(), [](const Connection* a, const Connection* b) {
                      if ((a->state == ConnState::kClosing) != (b->state == ConnState::kClosing))
                        return a->state == ConnState::kClosing;
                      return a->last_activity < b->last_activity;
                    });
  for (size_t i = 0; i < tries; ++i) {
    Connection* conn = candidates[i];
    if (conn->state == ConnState::kReading && Drain(conn) &&
        TryDispatch(conn) != Dispatch::kIncomplete)
      continue;  // dispatched (or closed for a bad request): not idle after all
    if (connections_.count(conn->fd) && connections_.at(conn->fd).get() == conn) Close(conn);
    Count(&HttpServerStats::closed_evicted);
    return true;
  }
  return false;
}

// Reads what has arrived without blocking; false when the client has closed
// (a complete request already read is still answered) or the read failed.
bool HttpServer::Impl::Drain(Connection* conn) {
  char buffer[16384];
  const size_t cap = options_.max_header_bytes + options_.max_body_bytes + 4;
  while (conn->in.size() <= cap) {
    const ssize_t n = ::recv(conn->fd, buffer, sizeof buffer, 0);
    if (n > 0) {
      if (conn->in.empty()) conn->first_byte = Clock::now();
      if (conn->state != ConnState::kClosing) conn->in.append(buffer, static_cast<size_t>(n));
      conn->last_activity = Clock::now();
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    conn->peer_closed = true;
    return false;
  }
  return true;
}

void HttpServer::Impl::ReadFrom(Connection* conn) {
  const bool open = Drain(conn);
  const Dispatch result = TryDispatch(conn);
  if (result == Dispatch::kIncomplete && !open) Close(conn);
}

void HttpServer::Impl::Watch(Connection* conn, uint32_t events) {
  epoll_event event{events, {.fd = conn->fd}};
  epoll_ctl(epoll_fd_, conn->watched ? EPOLL_CTL_MOD : EPOLL_CTL_ADD, conn->fd, &event);
  conn->watched = true;
}

void HttpServer::Impl::Unwatch(Connection* conn) {
  if (conn->watched) epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, conn->fd, nullptr);
  conn->watched = false;
}

void HttpServer::Impl::Close(Connection* conn) {
  Unwatch(conn);
  ::close(conn->fd);
  const auto it = per_client_.find(conn->remote_addr);
  if (it != per_client_.end() && --it->second <= 0) per_client_.erase(it);
  --open_connections_;
  connections_.erase(conn->fd);
}

// Answers `status` and closes once the answer is written.
void HttpServer::Impl::Refuse(Connection* conn, int status, const std::string& message) {
  HttpResponse res;
  res.status = status;
  res.SetContent(message + "\n", "text/plain; charset=utf-8");
  conn->in.clear();
  Respond(conn, ResponseText(res, false), false);
}

HttpServer::Impl::Dispatch HttpServer::Impl::TryDispatch(Connection* conn) {
  const size_t from = conn->scanned >= 3 ? conn->scanned - 3 : 0;
  const size_t head_end = conn->in.find("\r\n\r\n", from);
  if (head_end == std::string::npos || head_end > options_.max_header_bytes) {
    conn->scanned = conn->in.size();
    if (conn->in.size() <= options_.max_header_bytes) return Dispatch::kIncomplete;
    Refuse(conn, 431, "headers too large");
    return Dispatch::kClosed;
  }
  RequestHead head = ParseRequestHead(conn->in.substr(0, head_end), 2048, options_.max_body_bytes);
  if (head.refuse_status) {
    Refuse(conn, head.refuse_status, head.refuse_message);
    return Dispatch::kClosed;
  }
  const size_t total = head_end + 4 + head.body_size;
  if (conn->in.size() < total) {
    if (!conn->sent_continue && Lower(head.request.Header("expect")) == "100-continue") {
      conn->sent_continue = true;
      (void)!::send(conn->fd, "HTTP/1.1 100 Continue\r\n\r\n", 25, MSG_NOSIGNAL | MSG_DONTWAIT);
    }
    return Dispatch::kIncomplete;
  }
  head.request.body = conn->in.substr(head_end + 4, head.body_size);
  conn->in.erase(0, total);
  if (conn->in.capacity() > 64 * 1024) conn->in.shrink_to_fit();
  conn->scanned = 0;
  conn->sent_continue = false;
  if (!conn->in.empty()) conn->first_byte = Clock::now();
  return Route(conn, std::move(head));
}

// Screens and routes a complete request on the loop: refusals and unknown
// paths are answered here, the rest goes to its route's lane.
HttpServer::Impl::Dispatch HttpServer::Impl::Route(Connection* conn, RequestHead head) {
  Job job;
  job.request = std::move(head.request);
  job.request.remote_addr = conn->remote_addr;
  job.http11 = head.http11;
  const std::string connection = Lower(job.request.Header("connection"));
  job.keep_alive = head.http11 ? connection.find("close") == std::string::npos
                               : connection.find("keep-alive") != std::string::npos;
  Count(&HttpServerStats::requests);
  HttpResponse res;
  if (screen_ && screen_(job.request, res)) {
    Respond(conn, ResponseText(res, job.keep_alive), job.keep_alive);
    return Dispatch::kDispatched;
  }
  for (const RouteEntry& route : routes_) {
    std::smatch match;
    if (route.method != job.request.method ||
        !std::regex_match(job.request.path, match, route.pattern))
      continue;
    for (const auto& group : match) job.request.matches.push_back(group.str());
    job.route = &route;
    break;
  }
  if (!job.route) {
    Respond(conn, ResponseText(JsonError(404, "no such page"), job.keep_alive), job.keep_alive);
    return Dispatch::kDispatched;
  }
  job.conn = conn;
  conn->state = ConnState::kBusy;
  Unwatch(conn);
  Lane& lane = job.route->lane == HttpLane::kUrgent ? urgent_ : normal_;
  {
    std::lock_guard<std::mutex> lock(lane.mutex);
    lane.jobs.push_back(std::move(job));
  }
  lane.ready.notify_one();
  return Dispatch::kDispatched;
}

// Starts writing `text`; the rest is written as the client takes it.
void HttpServer::Impl::Respond(Connection* conn, std::string text, bool keep_alive) {
  conn->out = std::move(text);
  conn->out_sent = 0;
  conn->close_after_write = !keep_alive;
  conn->state = ConnState::kWriting;
  // A slow reader gets write_timeout plus a second per 64 KiB of the response.
  conn->out_deadline =
      Clock::now() + options_.write_timeout + std::chrono::seconds(conn->out.size() / (64 * 1024));
  conn->last_activity = Clock::now();
  Flush(conn);
}

void HttpServer::Impl::Flush(Connection* conn) {
  while (conn->out_sent < conn->out.size()) {
    const ssize_t n = ::send(conn->fd, conn->out.data() + conn->out_sent,
                             conn->out.size() - conn->out_sent, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      conn->out_sent += static_cast<size_t>(n);
      conn->last_activity = Clock::now();
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return Watch(conn, EPOLLOUT);
    return Close(conn);
  }
  conn->out.clear();
  conn->out.shrink_to_fit();
  AfterResponse(conn);
}

// The response is written: the next request, or a graceful close.
void HttpServer::Impl::AfterResponse(Connection* conn) {
  if (conn->close_after_write || stopping_.load()) {
    // Shut down for writing and read until the client closes, so that the
    // answer is not lost to a reset of unread input.
    ::shutdown(conn->fd, SHUT_WR);
    conn->state = ConnState::kClosing;
    conn->in.clear();
    if (!Drain(conn)) return Close(conn);
    return Watch(conn, EPOLLIN | EPOLLRDHUP);
  }
  conn->state = ConnState::kReading;
  const Dispatch next = TryDispatch(conn);
  if (next != Dispatch::kIncomplete) return;
  if (conn->peer_closed) return Close(conn);
  Watch(conn, EPOLLIN | EPOLLRDHUP);
}

void HttpServer::Impl::SweepTimeouts() {
  const Clock::time_point now = Clock::now();
  last_sweep_ = now;
  std::vector<Connection*> slow, idle, stalled;
  for (const auto& [fd, conn] : connections_) {
    switch (conn->state) {
      case ConnState::kReading:
        if (!conn->in.empty() && now - conn->first_byte > options_.request_timeout)
          slow.push_back(conn.get());
        else if (conn->in.empty() && now - conn->last_activity > options_.idle_timeout)
          idle.push_back(conn.get());
        break;
      case ConnState::kWriting:
        if (now > conn->out_deadline) stalled.push_back(conn.get());
        break;
      case ConnState::kClosing:
        if (now - conn->last_activity > std::chrono::seconds(1)) stalled.push_back(conn.get());
        break;
      case ConnState::kBusy:
        break;
    }
  }
  for (auto* list : {&slow, &idle, &stalled}) {
    for (Connection* conn : *list) Close(conn);
  }
  if (listen_paused_) {
    epoll_event resumed{EPOLLIN, {.fd = listen_fd_}};
    epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, listen_fd_, &resumed);
    listen_paused_ = false;
  }
  Count(&HttpServerStats::closed_slow, slow.size() + stalled.size());
  Count(&HttpServerStats::closed_idle, idle.size());
}

void HttpServer::Impl::TakeBackReturned() {
  std::vector<Returned> returned;
  {
    std::lock_guard<std::mutex> lock(returned_mutex_);
    returned.swap(returned_);
  }
  for (Returned& r : returned) {
    if (r.out.empty()) {
      Close(r.conn);
      continue;
    }
    r.conn->last_activity = Clock::now();
    Respond(r.conn, std::move(r.out), r.keep_alive);
  }
}

void HttpServer::Impl::ReturnToLoop(Connection* conn, std::string out, bool keep_alive) {
  {
    std::lock_guard<std::mutex> lock(returned_mutex_);
    returned_.push_back({conn, std::move(out), keep_alive});
  }
  Wake();
}

void HttpServer::Impl::WorkerMain(Lane* lane) {
  while (true) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(lane->mutex);
      lane->ready.wait(lock, [&] { return stopping_.load() || !lane->jobs.empty(); });
      if (stopping_.load()) return;
      job = std::move(lane->jobs.front());
      lane->jobs.pop_front();
    }
    Serve(std::move(job));
  }
}

void HttpServer::Impl::Serve(Job job) {
  HttpResponse res;
  try {
    job.route->handler(job.request, res);
  } catch (const std::exception& e) {
    LogError("http: " + job.request.method + " " + job.request.path + ": " + e.what());
    res = JsonError(500, "internal error; see the console's log");
  } catch (...) {
    LogError("http: " + job.request.method + " " + job.request.path + ": unknown exception");
    res = JsonError(500, "internal error; see the console's log");
  }
  if (res.stream) return StartStream(std::move(job), std::move(res));
  ReturnToLoop(job.conn, ResponseText(res, job.keep_alive), job.keep_alive);
}

// A stream's writes: chunks for HTTP/1.1, raw bytes until the close for 1.0.
class StreamWriter : public HttpStreamSink {
 public:
  StreamWriter(int fd, bool chunked, std::chrono::milliseconds timeout)
      : fd_(fd), chunked_(chunked), timeout_(timeout) {}
  bool Write(const std::string& data) override {
    if (!alive_ || data.empty()) return alive_;
    if (!chunked_) return alive_ = WriteAll(fd_, data.data(), data.size(), timeout_);
    char size_line[32];
    const int n = std::snprintf(size_line, sizeof size_line, "%zx\r\n", data.size());
    const std::string chunk = std::string(size_line, static_cast<size_t>(n)) + data + "\r\n";
    return alive_ = WriteAll(fd_, chunk.data(), chunk.size(), timeout_);
  }
  bool WriteHead(const std::string& head) {
    return alive_ = WriteAll(fd_, head.data(), head.size(), timeout_);
  }
  void Finish() {
    if (alive_ && chunked_) alive_ = WriteAll(fd_, "0\r\n\r\n", 5, timeout_);
  }
  bool alive() const { return alive_; }

 private:
  int fd_;
  bool chunked_;
  std::chrono::milliseconds timeout_;
  bool alive_ = true;
};

void HttpServer::Impl::StreamMain(Connection* conn, const HttpResponse& res, bool http11) {
  StreamWriter writer(conn->fd, http11, options_.write_timeout);
  if (writer.WriteHead(
          StatusLineAndHeaders(res, false, http11 ? Framing::kChunked : Framing::kUntilClose))) {
    try {
      while (writer.alive() && !stopping_.load() && res.stream(writer)) {
      }
    } catch (...) {
      LogError("http: a stream's writer threw; the stream is closed");
    }
    writer.Finish();
  }
  if (res.on_stream_end) res.on_stream_end();
  ReturnToLoop(conn, "", false);
}

void HttpServer::Impl::StartStream(Job job, HttpResponse response) {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  for (auto it = streams_.begin(); it != streams_.end();) {
    if (!(*it)->done.load()) {
      ++it;
      continue;
    }
    (*it)->thread.join();
    it = streams_.erase(it);
  }
  if (static_cast<int>(streams_.size()) >= options_.max_streams || stopping_.load()) {
    Count(&HttpServerStats::refused_streams);
    if (response.on_stream_end) response.on_stream_end();
    return ReturnToLoop(job.conn, ResponseText(JsonError(503, "too many streams open"), false),
                        false);
  }
  auto stream = std::make_unique<StreamThread>();
  StreamThread* raw = stream.get();
  raw->thread =
      std::thread([this, raw, conn = job.conn, http11 = job.http11, res = std::move(response)] {
        StreamMain(conn, res, http11);
        raw->done = true;
      });
  streams_.push_back(std::move(stream));
}

void HttpServer::Impl::Stop() {
  if (stopping_.exchange(true)) return;
  if (loop_.joinable()) {
    Wake();
    loop_.join();
  }
  // The loop has ended: every connection is here, and shutting the sockets
  // down ends the writes of streams and of any worker's client.
  for (const auto& [fd, conn] : connections_) ::shutdown(fd, SHUT_RDWR);
  for (Lane* lane : {&urgent_, &normal_}) {
    { std::lock_guard<std::mutex> lock(lane->mutex); }
    lane->ready.notify_all();
    for (std::thread& t : lane->threads) t.join();
    lane->threads.clear();
  }
  {
    std::lock_guard<std::mutex> lock(streams_mutex_);
    for (auto& stream : streams_) stream->thread.join();
    streams_.clear();
  }
  for (const auto& [fd, conn] : connections_) ::close(fd);
  connections_.clear();
  for (int* fd : {&listen_fd_, &epoll_fd_, &wake_fd_}) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
}

HttpServerStats HttpServer::Impl::Stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  HttpServerStats stats = stats_;
  stats.open_connections = open_connections_.load();
  return stats;
}

HttpServer::HttpServer(HttpServerOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}
HttpServer::~HttpServer() = default;
void HttpServer::Route(const std::string& method, const std::string& pattern, Handler handler,
                       HttpLane lane) {
  impl_->AddRoute(method, pattern, std::move(handler), lane);
}
void HttpServer::SetScreen(Screen screen) { impl_->SetScreen(std::move(screen)); }
Status HttpServer::Listen(const std::string& host, int port) { return impl_->Listen(host, port); }
int HttpServer::port() const { return impl_->port(); }
void HttpServer::Stop() { impl_->Stop(); }
HttpServerStats HttpServer::Stats() const { return impl_->Stats(); }

}  // namespace hairrig
