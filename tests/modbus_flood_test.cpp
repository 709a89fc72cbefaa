// The simulated Modbus TCP controller under a flood of held connections,
// past FD_SETSIZE (libmodbus' select() aborted the process at about 1,000),
// while its client (drivers/modbus_link.h) keeps reading registers. Its own
// executable: it raises the open-file limit, and skips (77) where it cannot.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/select.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "drivers/modbus_link.h"
#include "tests/support/modbus_tcp_peer.h"
#include "tests/support/open_file_limit.h"

namespace hairrig {
namespace {

using namespace hairrig_test;

constexpr int kFlood = 1200;

TEST(ModbusServerFlood, HeldConnectionFloodNeitherStopsTheServerNorLocksOutItsClient) {
  if (!hairrig_test::AllowOpenFiles(kFlood + 512))
    GTEST_SKIP() << "cannot open " << kFlood << " files in this process";
  TcpServerBench b;
  ModbusEndpoint endpoint;
  endpoint.host = b.server->host();
  endpoint.port = b.server->port();
  endpoint.slave_id = kUnit;
  endpoint.timeout_ms = 5000;
  endpoint.retries = 0;  // a reconnect during the flood would get a descriptor past FD_SETSIZE
  ModbusLink link(endpoint);
  ASSERT_TRUE(
      link.Connect().ok());  // before the flood: libmodbus' client select()s on its descriptor
  const int status_register = ModbusRegisterMap{}.status;
  ASSERT_TRUE(link.Read(status_register, 1).ok());
  std::vector<int> flood;
  while (flood.size() < static_cast<size_t>(kFlood)) {
    for (int i = 0; i < 100; ++i) {
      const int fd = StartConnection(*b.server);
      ASSERT_GE(fd, 0) << "connection " << flood.size() << ": " << std::strerror(errno);
      flood.push_back(fd);
    }
    auto read = link.Read(status_register, 1);
    ASSERT_TRUE(read.ok()) << "with " << flood.size()
                           << " connections open: " << read.status().ToString();
  }
  std::this_thread::sleep_for(
      std::chrono::milliseconds(200));  // every connection reaches the server
  for (int i = 0; i < 20; ++i)
    ASSERT_TRUE(link.Read(status_register, 1).ok()) << "read " << i << " after the flood";
  // The flood put this process (server included) past FD_SETSIZE descriptors.
  EXPECT_GT(*std::max_element(flood.begin(), flood.end()), FD_SETSIZE);
  // A newcomer still gets in (a silent connection makes room).
  const int late = ConnectTo(*b.server);
  ASSERT_GE(late, 0);
  EXPECT_EQ(Exchange(late, ReadRequest(kUnit, status_register), kReplyWait).size(), 11u);
  close(late);
  for (int fd : flood) close(fd);
  EXPECT_TRUE(link.Read(status_register, 1).ok());
}

}  // namespace
}  // namespace hairrig
