// Plain-socket HTTP for tests that need what a library client hides: idle and
// slow connections, one byte at a time, a request timed from its first byte.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <string>

namespace hairrig_test {

// A TCP connection to 127.0.0.1:port (-1 when refused).
inline int ConnectLoopback(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

inline bool SendText(int fd, const std::string& text) {
  size_t sent = 0;
  while (sent < text.size()) {
    const ssize_t n = ::send(fd, text.data() + sent, text.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return false;
    sent += static_cast<size_t>(n);
  }
  return true;
}

// True when the peer has closed the connection (or it failed); false while it
// is open with nothing to read.
inline bool PeerClosed(int fd) {
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, 0) <= 0) return false;
  char byte;
  return ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT) <= 0;
}

struct RawResponse {
  int status = 0;  // 0: no complete response within the timeout
  std::string head;
  std::string body;
  double seconds = 0;  // from the request's first byte to the response's last
};

// A request with "Connection: close"; reads the whole response (until the
// server closes) within `timeout`.
inline RawResponse RawRequest(int port, const std::string& method, const std::string& path,
                              const std::string& body = "", const std::string& extra_headers = "",
                              std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
  RawResponse res;
  const auto start = std::chrono::steady_clock::now();
  const int fd = ConnectLoopback(port);
  if (fd < 0) return res;
  std::string request = method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + extra_headers +
                        "Connection: close\r\n";
  if (!body.empty() || method == "POST")
    request +=
        "Content-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) + "\r\n";
  request += "\r\n" + body;
  std::string text;
  if (SendText(fd, request)) {
    const auto deadline = start + timeout;
    char buffer[8192];
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      pollfd p{fd, POLLIN, 0};
      if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) <= 0) {
        text.clear();
        break;
      }
      const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      text.append(buffer, static_cast<size_t>(n));
    }
  }
  ::close(fd);
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const size_t end = text.find("\r\n\r\n");
  if (end == std::string::npos || text.size() < 12) return res;
  res.head = text.substr(0, end);
  res.body = text.substr(end + 4);
  res.status = std::stoi(text.substr(9, 3));
  return res;
}

}  // namespace hairrig_test
