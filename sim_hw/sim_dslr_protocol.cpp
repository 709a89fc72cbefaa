#include "sim_hw/sim_dslr_protocol.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>

namespace hairrig::sim_dslr {
namespace {

constexpr size_t kMaxHeader = 64 * 1024;
constexpr size_t kMaxPayload = size_t{1} << 30;

std::string Clean(const std::string& field) {
  std::string out = field;
  for (char& c : out) {
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  }
  return out;
}

IoResult WaitReadable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  for (;;) {
    const int n = poll(&p, 1, timeout_ms);
    if (n > 0) return IoResult::kOk;
    if (n == 0) return IoResult::kTimeout;
    if (errno != EINTR) return IoResult::kClosed;
  }
}

// Reads exactly `size` bytes into `out`.
IoResult ReadExact(int fd, int timeout_ms, char* out, size_t size) {
  size_t done = 0;
  while (done < size) {
    const IoResult ready = WaitReadable(fd, timeout_ms);
    if (ready != IoResult::kOk) return ready;
    const ssize_t n = read(fd, out + done, size - done);
    if (n == 0) return IoResult::kClosed;
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      return IoResult::kClosed;
    }
    done += static_cast<size_t>(n);
  }
  return IoResult::kOk;
}

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, separator)) parts.push_back(part);
  if (!text.empty() && text.back() == separator) parts.emplace_back();
  return parts;
}

}  // namespace

const std::string& Message::field(size_t i) const {
  static const std::string kEmpty;
  return i < fields.size() ? fields[i] : kEmpty;
}

IoResult WriteMessage(int fd, uint64_t id, const std::vector<std::string>& fields,
                      const std::string& payload) {
  std::string header = std::to_string(id) + '\t';
  for (const std::string& f : fields) header += Clean(f) + '\t';
  header += std::to_string(payload.size()) + '\n';
  const std::string data = header + payload;
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = send(fd, data.data() + done, data.size() - done, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      return IoResult::kClosed;
    }
    done += static_cast<size_t>(n);
  }
  return IoResult::kOk;
}

IoResult ReadMessage(int fd, int timeout_ms, Message* out) {
  std::string header;
  for (;;) {
    char c = 0;
    const IoResult r = ReadExact(fd, timeout_ms, &c, 1);
    if (r != IoResult::kOk) return r;
    if (c == '\n') break;
    header += c;
    if (header.size() > kMaxHeader) return IoResult::kMalformed;
  }
  std::vector<std::string> fields = Split(header, '\t');
  if (fields.size() < 3) return IoResult::kMalformed;
  char* id_end = nullptr;
  const unsigned long long id = std::strtoull(fields.front().c_str(), &id_end, 10);
  if (fields.front().empty() || *id_end != '\0') return IoResult::kMalformed;
  fields.erase(fields.begin());
  char* end = nullptr;
  const unsigned long long size = std::strtoull(fields.back().c_str(), &end, 10);
  if (fields.back().empty() || *end != '\0' || size > kMaxPayload) return IoResult::kMalformed;
  fields.pop_back();
  out->id = id;
  out->fields = std::move(fields);
  out->payload.assign(static_cast<size_t>(size), '\0');
  if (size == 0) return IoResult::kOk;
  return ReadExact(fd, timeout_ms, out->payload.data(), out->payload.size());
}

std::string SocketPathForPort(const std::string& port_path) {
  std::string folder = port_path;
  if (folder.rfind("disk:", 0) == 0) folder = folder.substr(5);
  if (folder.empty()) return "";
  while (folder.size() > 1 && folder.back() == '/') folder.pop_back();
  const std::string path = folder + "/" + kSocketName;
  if (path.size() >= sizeof(sockaddr_un::sun_path)) return "";
  return path;
}

int ConnectUnix(const std::string& path) {
  sockaddr_un address{};
  if (path.empty() || path.size() >= sizeof(address.sun_path)) {
    errno = ENAMETOOLONG;
    return -1;
  }
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  if (connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    const int saved = errno;
    close(fd);
    errno = saved;
    return -1;
  }
  return fd;
}

std::string EncodeConfig(const std::vector<ConfigItem>& items) {
  std::string out;
  for (const ConfigItem& item : items) {
    std::string choices;
    for (const std::string& c : item.choices) choices += (choices.empty() ? "" : "|") + Clean(c);
    out += Clean(item.name) + '\t' + Clean(item.label) + '\t' + Clean(item.section) + '\t' +
           (item.read_only ? "ro" : "rw") + '\t' + Clean(item.value) + '\t' + choices + '\n';
  }
  return out;
}

std::vector<ConfigItem> DecodeConfig(const std::string& payload) {
  std::vector<ConfigItem> items;
  for (const std::string& line : Split(payload, '\n')) {
    const std::vector<std::string> f = Split(line, '\t');
    if (f.size() < 6) continue;
    ConfigItem item{f[0], f[1], f[2], f[3] == "ro", f[4], {}};
    if (!f[5].empty()) item.choices = Split(f[5], '|');
    items.push_back(std::move(item));
  }
  return items;
}

}  // namespace hairrig::sim_dslr
