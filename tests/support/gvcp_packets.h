// Test helper: GVCP (GigE Vision control) command packets, the hostile ones
// that crashed Aravis' GigE fake camera, and a one-shot UDP exchange.
// Header-only, for tests.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <string>
#include <vector>

namespace hairrig_test {

inline constexpr uint16_t kGvcpDiscovery = 0x0002;
inline constexpr uint16_t kGvcpReadRegister = 0x0080;
inline constexpr uint16_t kGvcpWriteRegister = 0x0082;
inline constexpr uint16_t kGvcpReadMemory = 0x0084;
inline constexpr uint16_t kGvcpWriteMemory = 0x0086;
inline constexpr uint32_t kFakeTestRegister = 0x1f0;  // Aravis' fake: reads 0x12345678

// A GVCP command: key 0x42, flags, command, length (`length`, or the words'
// bytes when negative), request id 1, then the words big-endian.
inline std::vector<uint8_t> GvcpCommand(uint16_t command, const std::vector<uint32_t>& words,
                                        int length = -1) {
  const int n = length >= 0 ? length : static_cast<int>(4 * words.size());
  std::vector<uint8_t> p = {0x42,
                            0x01,
                            static_cast<uint8_t>(command >> 8),
                            static_cast<uint8_t>(command),
                            static_cast<uint8_t>(n >> 8),
                            static_cast<uint8_t>(n),
                            0,
                            1};
  for (uint32_t w : words) {
    for (int shift = 24; shift >= 0; shift -= 8) p.push_back(static_cast<uint8_t>(w >> shift));
  }
  return p;
}

// Packets each of which crashed Aravis 0.8's GigE fake camera (reads and
// writes outside its memory, sizes that wrap).
inline std::vector<std::vector<uint8_t>> HostileGvcpPackets() {
  return {GvcpCommand(kGvcpReadMemory, {0xFFFFFFF0, 4}),
          GvcpCommand(kGvcpReadMemory, {0x00100000, 512}),
          GvcpCommand(kGvcpReadRegister, {0xFFFFFFFE}),
          GvcpCommand(kGvcpWriteRegister, {0xFFFFFFFC, 7}),
          GvcpCommand(kGvcpWriteMemory, {0xFFFFFFFC, 9, 9}),
          GvcpCommand(kGvcpWriteMemory, {8}, 2)};
}

// Sends `packet` to `host`:3956 and returns the size of the reply within
// `wait_ms`; -1 for none.
inline int AskGvcp(const std::string& host, const std::vector<uint8_t>& packet, int wait_ms = 500) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(3956);
  inet_pton(AF_INET, host.c_str(), &a.sin_addr);
  sendto(fd, packet.data(), packet.size(), 0, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  pollfd p{fd, POLLIN, 0};
  int size = -1;
  if (poll(&p, 1, wait_ms) == 1) {
    std::vector<uint8_t> reply(70000);
    size = static_cast<int>(recv(fd, reply.data(), reply.size(), 0));
  }
  close(fd);
  return size;
}

}  // namespace hairrig_test
