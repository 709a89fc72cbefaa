// The libusb enumeration of the `usbrelay` backend against a USB relay board
// that umockdev fakes in sysfs and udev (tests/data/usb_relay.umockdev: the
// attributes and descriptors of a 16c0:05df "USBRelay2" board, written for
// this test). ctest runs this binary under `umockdev-run`; run alone, it
// reports itself skipped.
#include <gtest/gtest.h>

#include <cstdlib>

#include "drivers/usb_relay.h"
#include "drivers/usb_relay_discovery.h"

namespace hairrig {
namespace {

TEST(UsbRelayUmockdev, TheBoardIsEnumeratedAtItsPortAndItsProblemsNamed) {
  if (std::getenv("UMOCKDEV_DIR") == nullptr) {
    GTEST_SKIP() << "not under umockdev-run (ctest runs it there: ctest -R usb_relay_umockdev)";
  }
  auto bus = MakeLibusbRelayBus();
  auto boards = bus->List();
  ASSERT_TRUE(boards.ok()) << boards.status().ToString();
  ASSERT_EQ(boards->size(), 1u);
  EXPECT_EQ((*boards)[0].port_path, "1-3");
  const auto found = DetectUsbRelays(*bus);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].port_path, "1-3");
  // umockdev has no USB traffic to answer with: the exchange fails, and says where.
  if (found[0].board_id.empty()) {
    EXPECT_NE(found[0].error.find("USB port 1-3"), std::string::npos) << found[0].error;
  }
}

}  // namespace
}  // namespace hairrig
