#include "console/estop_client.h"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/json_file.h"
#include "core/string_format.h"

namespace hairrig {

namespace {

using Clock = std::chrono::steady_clock;

struct HostPort {
  std::string host;
  std::string port;
};

Result<HostPort> ParseUrl(const std::string& url) {
  const std::string scheme = "http://";
  if (url.rfind(scheme, 0) != 0)
    return InvalidArgument("url: expected http://host:port/, got '" + url + "'");
  std::string rest = url.substr(scheme.size());
  rest = rest.substr(0, rest.find('/'));
  HostPort hp;
  const size_t colon = rest.rfind(':');
  if (colon == std::string::npos || colon + 1 == rest.size())
    return InvalidArgument("url: no port in '" + url + "'");
  hp.host = rest.substr(0, colon);
  hp.port = rest.substr(colon + 1);
  if (hp.host.size() > 2 && hp.host.front() == '[' && hp.host.back() == ']')
    hp.host = hp.host.substr(1, hp.host.size() - 2);
  if (hp.host.empty() || hp.port.find_first_not_of("0123456789") != std::string::npos)
    return InvalidArgument("url: expected http://host:port/, got '" + url + "'");
  return hp;
}

int MillisLeft(Clock::time_point deadline) {
  return static_cast<int>(std::max<int64_t>(
      0, std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count()));
}

// A connected socket to host:port before `deadline`, or -1.
int ConnectBefore(const HostPort& hp, Clock::time_point deadline) {
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(hp.host.c_str(), hp.port.c_str(), &hints, &found) != 0) return -1;
  int fd = -1;
  for (addrinfo* a = found; a && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) continue;
    const int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (rc != 0 && errno != EINPROGRESS) {
      ::close(fd);
      fd = -1;
      continue;
    }
    if (rc == 0) break;
    pollfd p{fd, POLLOUT, 0};
    int error = 0;
    socklen_t length = sizeof error;
    if (::poll(&p, 1, MillisLeft(deadline)) != 1 ||
        getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length) != 0 || error != 0) {
      ::close(fd);
      fd = -1;
    }
  }
  freeaddrinfo(found);
  return fd;
}

// Sends `request` and reads the whole answer (the server closes) before `deadline`.
bool Exchange(int fd, const std::string& request, Clock::time_point deadline, std::string* answer) {
  size_t sent = 0;
  while (sent < request.size()) {
    const ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<size_t>(n);
      continue;
    }
    pollfd p{fd, POLLOUT, 0};
    if (n < 0 && errno != EAGAIN) return false;
    if (::poll(&p, 1, MillisLeft(deadline)) != 1) return false;
  }
  char buffer[4096];
  while (true) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, MillisLeft(deadline)) != 1) return false;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n == 0) return true;
    if (n < 0 && errno != EAGAIN) return false;
    if (n > 0) answer->append(buffer, static_cast<size_t>(n));
  }
}

}  // namespace

Status EStopRequest::Check() const {
  HR_RETURN_IF_ERROR(ParseUrl(url).status());
  if (timeout.count() <= 0) return InvalidArgument("timeout: must be positive");
  return Status::Ok();
}

Result<EStopSummary> PressConsoleEStop(const EStopRequest& request) {
  HR_RETURN_IF_ERROR(request.Check());
  HR_ASSIGN_OR_RETURN(const HostPort hp, ParseUrl(request.url));
  const Clock::time_point start = Clock::now();
  const Clock::time_point deadline = start + request.timeout;
  const std::string no_answer =
      "the console at " + request.url + " did not answer: press the rig's hardware e-stop";
  const int fd = ConnectBefore(hp, deadline);
  if (fd < 0) return Unavailable(no_answer + " (cannot connect)");
  const std::string body = nlohmann::json{{"client", request.who}}.dump();
  std::string text = "POST /api/estop HTTP/1.1\r\nHost: " + hp.host + ":" + hp.port +
                     "\r\nConnection: close\r\nContent-Type: application/json\r\nContent-Length: " +
                     std::to_string(body.size()) + "\r\n";
  if (!request.token.empty()) text += "Authorization: Bearer " + request.token + "\r\n";
  std::string answer;
  const bool answered = Exchange(fd, text + "\r\n" + body, deadline, &answer);
  ::close(fd);
  if (!answered)
    return Unavailable(no_answer + StringPrintf(" within %lld ms",
                                                static_cast<long long>(request.timeout.count())));
  const size_t end = answer.find("\r\n\r\n");
  if (end == std::string::npos || answer.size() < 12)
    return Unavailable(no_answer + " (a malformed answer)");
  const int status = std::atoi(answer.substr(9, 3).c_str());
  const nlohmann::json reply = nlohmann::json::parse(answer.substr(end + 4), nullptr, false);
  if (status != 200) {
    const std::string why =
        reply.is_object() && reply.contains("error") && reply["error"].is_string()
            ? reply["error"].get<std::string>()
            : "HTTP " + std::to_string(status);
    return FailedPrecondition("the console at " + request.url + " refused the e-stop: " + why);
  }
  EStopSummary summary;
  summary.url = request.url;
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (reply.is_object() && reply.contains("estop") && reply["estop"].is_object()) {
    summary.active = reply["estop"].value("active", false);
    summary.reason = reply["estop"].value("reason", "");
  }
  if (!summary.active)
    return Unavailable("the console at " + request.url +
                       " answered without an active e-stop: press the rig's hardware e-stop");
  return summary;
}

nlohmann::json EStopSummary::ToJson() const {
  return {{"url", url}, {"active", active}, {"reason", reason}, {"seconds", seconds}};
}

std::string EStopSummary::BriefReport() const {
  return StringPrintf("e-stop active at %s (%s), answered in %.0f ms\n", url.c_str(),
                      reason.c_str(), seconds * 1000);
}

}  // namespace hairrig
