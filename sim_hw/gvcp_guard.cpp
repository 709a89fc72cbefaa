#include "sim_hw/gvcp_guard.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <linux/filter.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

namespace hairrig {

namespace {

// A UDP socket's filter sees the UDP header (8 bytes) first; the GVCP
// command header follows: key 0x42, flags, command (2), length of what
// follows (2), request id (2); then the command's words.
constexpr uint32_t kGvcp = 8;
constexpr uint32_t kCommandHeaderEnd = kGvcp + 8;
constexpr uint32_t kFirstWord = kGvcp + 8;  // the address
constexpr uint32_t kSecondWord =
    kGvcp + 12;  // a register's value; a memory read's size (low 16 bits)
constexpr uint32_t kGvcpKey = 0x42;
constexpr uint32_t kDiscovery = 0x0002;
constexpr uint32_t kReadRegister = 0x0080;
constexpr uint32_t kWriteRegister = 0x0082;
constexpr uint32_t kReadMemory = 0x0084;
constexpr uint32_t kWriteMemory = 0x0086;

// A classic BPF program whose jumps go forward to named labels.
class FilterProgram {
 public:
  void Statement(uint16_t code, uint32_t k = 0) { code_.push_back(BPF_STMT(code, k)); }
  // To `if_true`, else to `if_false`; "" is the next instruction.
  void Jump(uint16_t code, uint32_t k, const std::string& if_true,
            const std::string& if_false = "") {
    jumps_.push_back({code_.size(), if_true, if_false});
    code_.push_back(BPF_JUMP(code, k, 0, 0));
  }
  void Label(const std::string& name) { labels_[name] = code_.size(); }

  std::vector<sock_filter> Resolve() const {
    std::vector<sock_filter> code = code_;
    for (const PendingJump& j : jumps_) {
      code[j.at].jt = Offset(j.at, j.if_true);
      code[j.at].jf = Offset(j.at, j.if_false);
    }
    return code;
  }

 private:
  struct PendingJump {
    size_t at;
    std::string if_true, if_false;
  };
  uint8_t Offset(size_t from, const std::string& label) const {
    return label.empty() ? 0 : static_cast<uint8_t>(labels_.at(label) - from - 1);
  }

  std::vector<sock_filter> code_;
  std::vector<PendingJump> jumps_;
  std::map<std::string, size_t> labels_;
};

constexpr uint16_t kLoadLength = BPF_LD | BPF_W | BPF_LEN;
constexpr uint16_t kLoadByte = BPF_LD | BPF_B | BPF_ABS;
constexpr uint16_t kLoadHalf = BPF_LD | BPF_H | BPF_ABS;
constexpr uint16_t kLoadWord = BPF_LD | BPF_W | BPF_ABS;
constexpr uint16_t kIfEqual = BPF_JMP | BPF_JEQ | BPF_K;
constexpr uint16_t kIfAtLeast = BPF_JMP | BPF_JGE | BPF_K;
constexpr uint16_t kIfAbove = BPF_JMP | BPF_JGT | BPF_K;

// A register read or write: its words present; a read's address at most
// `end` (the fake zero-fills what lies past its file), a write's 4 bytes
// below `end`.
void RegisterAccess(FilterProgram* p, const std::string& label, bool write, uint32_t end) {
  p->Label(label);
  p->Statement(kLoadLength);
  p->Jump(kIfAtLeast, kFirstWord + (write ? 8 : 4), "", "drop");
  p->Statement(kLoadWord, kFirstWord);
  p->Jump(kIfAbove, write ? std::max<uint32_t>(end, 4) - 4 : end, "drop", "accept");
}

// A memory read: address and size (its low 16 bits, not 0) present, and the
// address at most `end`: the fake copies up to its file's end and zero-fills
// the rest (clients round a read up to whole words).
void MemoryRead(FilterProgram* p, uint32_t end) {
  p->Label("read memory");
  p->Statement(kLoadLength);
  p->Jump(kIfAtLeast, kSecondWord + 4, "", "drop");
  p->Statement(kLoadWord, kSecondWord);
  p->Statement(BPF_ALU | BPF_AND | BPF_K, 0xFFFF);
  p->Jump(kIfEqual, 0, "drop");
  p->Statement(kLoadWord, kFirstWord);
  p->Jump(kIfAbove, end, "drop", "accept");
}

// A memory write: the header's length (4 address bytes + data) at least 8,
// all of it in the packet, and [address, address + data) below `end`.
void MemoryWrite(FilterProgram* p, uint32_t end) {
  p->Label("write memory");
  p->Statement(kLoadHalf, kGvcp + 4);
  p->Jump(kIfAtLeast, 8, "", "drop");
  p->Statement(BPF_MISC | BPF_TAX);
  p->Statement(kLoadLength);
  p->Statement(BPF_ALU | BPF_SUB | BPF_K, kCommandHeaderEnd);
  p->Jump(BPF_JMP | BPF_JGE | BPF_X, 0, "", "drop");
  p->Statement(kLoadHalf, kGvcp + 4);
  p->Statement(BPF_ALU | BPF_SUB | BPF_K, 4);
  p->Statement(BPF_MISC | BPF_TAX);
  p->Statement(kLoadWord, kFirstWord);
  p->Jump(kIfAbove, end, "drop");
  p->Statement(BPF_ALU | BPF_ADD | BPF_X);
  p->Jump(kIfAbove, end, "drop", "accept");
}

std::vector<sock_filter> GvcpFilter(GvcpMemoryLimits limits) {
  FilterProgram p;
  p.Statement(kLoadLength);
  p.Jump(kIfAtLeast, kCommandHeaderEnd, "", "drop");
  p.Statement(kLoadByte, kGvcp);
  p.Jump(kIfEqual, kGvcpKey, "", "drop");
  p.Statement(kLoadHalf, kGvcp + 2);
  p.Jump(kIfEqual, kDiscovery, "accept");
  p.Jump(kIfEqual, kReadRegister, "read register");
  p.Jump(kIfEqual, kWriteRegister, "write register");
  p.Jump(kIfEqual, kReadMemory, "read memory");
  p.Jump(kIfEqual, kWriteMemory, "write memory", "drop");
  RegisterAccess(&p, "read register", /*write=*/false, limits.readable_end);
  RegisterAccess(&p, "write register", /*write=*/true, limits.writable_end);
  MemoryRead(&p, limits.readable_end);
  MemoryWrite(&p, limits.writable_end);
  p.Label("accept");
  p.Statement(BPF_RET | BPF_K, 0xFFFFFFFF);
  p.Label("drop");
  p.Statement(BPF_RET | BPF_K, 0);
  return p.Resolve();
}

// The UDP socket's IPv4 address when `fd` is one bound to the GVCP port.
bool BoundToGvcpPort(int fd, sockaddr_in* bound) {
  int type = 0;
  socklen_t type_size = sizeof type;
  socklen_t size = sizeof *bound;
  return getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &type_size) == 0 && type == SOCK_DGRAM &&
         getsockname(fd, reinterpret_cast<sockaddr*>(bound), &size) == 0 &&
         bound->sin_family == AF_INET && ntohs(bound->sin_port) == kGvcpPort;
}

// The name of the interface with IPv4 address `address` ("lo"); "" if none.
std::string InterfaceWithAddress(in_addr address) {
  ifaddrs* all = nullptr;
  if (getifaddrs(&all) != 0) return "";
  std::string name;
  for (const ifaddrs* i = all; i != nullptr && name.empty(); i = i->ifa_next) {
    if (i->ifa_addr == nullptr || i->ifa_addr->sa_family != AF_INET) continue;
    if (reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr.s_addr == address.s_addr)
      name = i->ifa_name;
  }
  freeifaddrs(all);
  return name;
}

// The interface the socket is confined to; "" for none.
std::string BoundDevice(int fd) {
  char name[IFNAMSIZ] = {};
  socklen_t size = sizeof name;
  if (getsockopt(fd, SOL_SOCKET, SO_BINDTODEVICE, name, &size) != 0) return "";
  return std::string(name, strnlen(name, sizeof name));
}

// Puts an unbound UDP socket at `fd` (closing what was there): its owner
// keeps a valid descriptor that never becomes readable.
Status ReplaceWithUnboundSocket(int fd) {
  const int idle = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (idle < 0 || dup3(idle, fd, O_CLOEXEC) < 0) {
    const std::string reason = std::strerror(errno);
    if (idle >= 0) close(idle);
    return Internal("GVCP guard: cannot close the broadcast socket " + std::to_string(fd) + ": " +
                    reason);
  }
  close(idle);
  return Status::Ok();
}

// The inode of the socket at `fd` ("socket:[inode]" in /proc/self/fd, the
// inode column of /proc/net/udp); nullopt when `fd` is no socket.
std::optional<uint64_t> SocketInode(int fd) {
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISSOCK(st.st_mode)) return std::nullopt;
  return static_cast<uint64_t>(st.st_ino);
}

// Whether `fd` is a socket opened since `before` was taken (OpenSocketInodes).
bool OpenedSince(int fd, const std::set<uint64_t>& before) {
  const std::optional<uint64_t> inode = SocketInode(fd);
  return inode && before.count(*inode) == 0;
}

// A hexadecimal field of /proc/net/udp.
uint32_t ParseHex(const std::string& hex) {
  return static_cast<uint32_t>(std::strtoul(hex.c_str(), nullptr, 16));
}

// Whether a local address of /proc/net/udp ("0100007F", the 32-bit word as
// the kernel prints it) or udp6 (four such words) takes packets for `address`
// (the wildcard, `address` itself, or `address` mapped into IPv6).
bool TakesPacketsFor(const std::string& hex, in_addr address) {
  std::vector<uint32_t> words;
  for (size_t at = 0; at + 8 <= hex.size(); at += 8) words.push_back(ParseHex(hex.substr(at, 8)));
  if (words.size() == 1) return words[0] == 0 || words[0] == address.s_addr;
  if (words.size() != 4 || words[0] != 0 || words[1] != 0) return false;
  return (words[2] == 0 && words[3] == 0) ||
         (words[2] == htonl(0xFFFF) && words[3] == address.s_addr);
}

// Adds the inodes of the sockets in `table` (/proc/net/udp or udp6) that
// take packets for `address`:kGvcpPort; false when it cannot be read.
bool ReadGvcpServers(const char* table, in_addr address, std::set<uint64_t>* inodes) {
  std::ifstream in(table);
  if (!in) return false;
  std::string line;
  std::getline(in, line);  // the column names
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string slot, local, remote, state, queues, timer, retransmits, uid, timeout;
    uint64_t inode = 0;
    if (!(fields >> slot >> local >> remote >> state >> queues >> timer >> retransmits >> uid >>
          timeout >> inode)) {
      continue;
    }
    const size_t colon = local.find(':');
    if (colon == std::string::npos ||
        ParseHex(local.substr(colon + 1)) != static_cast<uint32_t>(kGvcpPort)) {
      continue;
    }
    if (TakesPacketsFor(local.substr(0, colon), address)) inodes->insert(inode);
  }
  return true;
}

// The inodes of the UDP sockets that take packets for `address`:kGvcpPort;
// nullopt when the kernel's table of IPv4 sockets cannot be read.
std::optional<std::set<uint64_t>> GvcpServerInodes(in_addr address) {
  std::set<uint64_t> inodes;
  if (!ReadGvcpServers("/proc/net/udp", address, &inodes)) return std::nullopt;
  (void)ReadGvcpServers("/proc/net/udp6", address, &inodes);  // absent without IPv6
  return inodes;
}

}  // namespace

Status RequireSoleGvcpServer(const std::set<uint64_t>& before,
                             const std::string& interface_address) {
  in_addr served{};
  if (inet_pton(AF_INET, interface_address.c_str(), &served) != 1) {
    return InvalidArgument("GVCP guard: '" + interface_address + "' is not an IPv4 address");
  }
  const std::optional<std::set<uint64_t>> servers = GvcpServerInodes(served);
  if (!servers) return Status::Ok();  // no /proc/net/udp to tell
  const std::string endpoint = interface_address + ":" + std::to_string(kGvcpPort);
  const std::set<uint64_t> open_now = OpenSocketInodes();
  bool served_here = false;
  for (uint64_t inode : *servers) {
    if (open_now.count(inode) != 0 && before.count(inode) == 0) {  // the fake's
      served_here = true;
      continue;
    }
    return Unavailable(endpoint + " is already served by another UDP socket (inode " +
                       std::to_string(inode) +
                       "): two GigE Vision cameras on one port take each other's packets, and "
                       "a client would get the other's answers and images");
  }
  if (!served_here) return Unavailable("the GigE fake camera could not bind " + endpoint);
  return Status::Ok();
}

Status AttachGvcpFilter(int fd, GvcpMemoryLimits limits) {
  std::vector<sock_filter> code = GvcpFilter(limits);
  const sock_fprog program{static_cast<unsigned short>(code.size()), code.data()};
  if (setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &program, sizeof program) != 0) {
    return Unavailable("GVCP guard: cannot attach the packet filter to socket " +
                       std::to_string(fd) + ": " + std::strerror(errno));
  }
  return Status::Ok();
}

std::set<int> OpenDescriptors() {
  std::set<int> fds;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.empty() && std::all_of(name.begin(), name.end(), ::isdigit))
      fds.insert(std::stoi(name));
  }
  return fds;
}

std::set<uint64_t> OpenSocketInodes() {
  std::set<uint64_t> inodes;
  for (int fd : OpenDescriptors()) {
    if (const std::optional<uint64_t> inode = SocketInode(fd)) inodes.insert(*inode);
  }
  return inodes;
}

Result<GvcpGuardSummary> GuardGvFakeSockets(const std::set<uint64_t>& before,
                                            const std::string& interface_address,
                                            GvcpMemoryLimits limits) {
  in_addr served{};
  if (inet_pton(AF_INET, interface_address.c_str(), &served) != 1) {
    return InvalidArgument("GVCP guard: '" + interface_address + "' is not an IPv4 address");
  }
  const std::string device = InterfaceWithAddress(served);
  GvcpGuardSummary summary;
  for (int fd : OpenDescriptors()) {
    sockaddr_in bound{};
    if (!OpenedSince(fd, before) || !BoundToGvcpPort(fd, &bound)) continue;
    HR_RETURN_IF_ERROR(AttachGvcpFilter(fd, limits));
    ++summary.filtered;
    if (bound.sin_addr.s_addr == served.s_addr) continue;
    if (!device.empty() &&
        (BoundDevice(fd) == device || setsockopt(fd, SOL_SOCKET, SO_BINDTODEVICE, device.c_str(),
                                                 static_cast<socklen_t>(device.size())) == 0)) {
      ++summary.confined;
      continue;
    }
    HR_RETURN_IF_ERROR(ReplaceWithUnboundSocket(fd));
    ++summary.closed;
  }
  if (summary.filtered == 0) {
    return Unavailable("GVCP guard: the GigE fake camera opened no UDP socket on port " +
                       std::to_string(kGvcpPort));
  }
  return summary;
}

}  // namespace hairrig
