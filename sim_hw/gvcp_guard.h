// A guard in front of Aravis' GigE Vision fake camera (ArvGvFakeCamera, used
// by sim_hw/sim_aravis.h). Its control-packet handler trusts every address
// and size a packet carries: in Aravis 0.8 one READMEM at 0xFFFFFFF0 (or any
// read past its GenICam file, or a write past its registers) makes it copy
// gigabytes and takes the whole process down. Its sockets are private, so
// the guard works on the descriptors the fake opened:
//   - a kernel socket filter (classic BPF, SO_ATTACH_FILTER) on each drops,
//     before the fake reads it, every packet but a GVCP command (key 0x42) of
//     discovery, register read or write, or memory read or write, and every
//     access outside the fake's memory: reads starting at most at
//     readable_end (the fake zero-fills past its file; clients round the
//     last read of the file up to whole words), writes inside
//     [0, writable_end), a memory write's data all present;
//   - a socket the fake bound to a broadcast address (255.255.255.255:3956,
//     for discovery) is confined to the fake's own interface
//     (SO_BINDTODEVICE), so discovery works on that interface and no other
//     network reaches the fake; where the kernel refuses that, the socket is
//     closed (an unbound socket takes its descriptor).
// A packet that arrives between the fake opening its sockets and the guard
// attaching (a few microseconds at start) is not filtered.
#pragma once

#include <cstdint>
#include <set>
#include <string>

#include "core/status.h"

namespace hairrig {

inline constexpr int kGvcpPort = 3956;

struct GvcpMemoryLimits {
  uint32_t readable_end = 0;  // registers, then the GenICam file
  uint32_t writable_end = 0;  // registers
};

// Attaches the GVCP filter to the UDP socket `fd`.
Status AttachGvcpFilter(int fd, GvcpMemoryLimits limits);

// The descriptors open in this process now.
std::set<int> OpenDescriptors();

// The inodes of the sockets open in this process now ("socket:[inode]" in
// /proc/self/fd): the `before` of GuardGvFakeSockets and
// RequireSoleGvcpServer, taken before the fake starts. A socket is told by
// its inode, not its descriptor: a descriptor closed meanwhile (by another
// thread) can be reused for one of the fake's sockets.
std::set<uint64_t> OpenSocketInodes();

struct GvcpGuardSummary {
  int filtered = 0;  // sockets on the GVCP port given the filter
  int confined = 0;  // broadcast sockets confined to the interface
  int closed = 0;    // broadcast sockets closed
};

// Guards the UDP sockets on the GVCP port opened since `before` (the fake
// camera's; `before` from OpenSocketInodes), the fake serving on the
// interface with IPv4 address `interface_address`. Unavailable when there is
// none, or the filter cannot be attached: the fake must not serve unguarded.
Result<GvcpGuardSummary> GuardGvFakeSockets(const std::set<uint64_t>& before,
                                            const std::string& interface_address,
                                            GvcpMemoryLimits limits);

// Checks that the GigE fake started since `before` alone serves
// `interface_address` on the GVCP port. Unavailable when a UDP socket not
// opened by this process since `before` (another process's, or one this
// process had before) takes packets sent there (bound to that address or to
// every address, IPv4 or IPv6, in this network namespace: /proc/net/udp,
// udp6), or when none of the new sockets is bound there; Ok when
// /proc/net/udp cannot be read. A second Aravis fake on the port starts
// without its control socket and answers discovery; a client would get the
// first one's answers and images.
Status RequireSoleGvcpServer(const std::set<uint64_t>& before,
                             const std::string& interface_address);

}  // namespace hairrig
