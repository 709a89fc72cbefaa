#include "console/control_lease.h"

#include <gtest/gtest.h>

#include <thread>

#include "console/event_hub.h"

namespace hairrig {
namespace {

using namespace std::chrono_literals;
using Clock = ControlLease::Clock;

TEST(ControlLease, OneHolderAtATimeUntilReleasedOrTaken) {
  ControlLease lease(15s);
  const Clock::time_point t0 = Clock::now();
  auto first = lease.Claim("operator-a", false, t0);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_EQ(first->lease.size(), 32u);
  EXPECT_EQ(lease.Holder(t0).value_or(""), "operator-a");

  auto second = lease.Claim("operator-b", false, t0 + 1s);
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(second.status().message().find("operator-a holds control"), std::string::npos);
  EXPECT_TRUE(lease.Check(first->lease, t0 + 2s));
  EXPECT_FALSE(lease.Check("0123456789abcdef0123456789abcdef", t0 + 2s));

  auto taken = lease.Claim("operator-b", true, t0 + 3s);
  ASSERT_TRUE(taken.ok());
  EXPECT_FALSE(lease.Check(first->lease, t0 + 3s)) << "the old lease must end when taken";
  EXPECT_TRUE(lease.Check(taken->lease, t0 + 3s));
  EXPECT_FALSE(lease.Release(first->lease));
  EXPECT_TRUE(lease.Release(taken->lease));
  EXPECT_FALSE(lease.Holder(t0 + 3s).has_value());
}

TEST(ControlLease, LapsesWhenTheHolderGoesQuietAndLivesWhileItSpeaks) {
  ControlLease lease(15s);
  const Clock::time_point t0 = Clock::now();
  auto grant = lease.Claim("page", false, t0);
  ASSERT_TRUE(grant.ok());
  // Heartbeats every 10 s keep it beyond the first 15 s.
  EXPECT_TRUE(lease.Check(grant->lease, t0 + 10s));
  EXPECT_TRUE(lease.Check(grant->lease, t0 + 20s));
  EXPECT_TRUE(lease.Holder(t0 + 34s).has_value());
  // Then silence: lapsed, and anyone may claim without taking.
  EXPECT_FALSE(lease.Holder(t0 + 36s).has_value());
  EXPECT_FALSE(lease.Check(grant->lease, t0 + 36s));
  EXPECT_TRUE(lease.Claim("other", false, t0 + 36s).ok());
}

TEST(ControlLease, ClientNamesAreChecked) {
  ControlLease lease;
  EXPECT_EQ(lease.Claim("", false).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(lease.Claim(std::string(65, 'a'), false).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(lease.Claim("bad\nname", false).status().code(), StatusCode::kInvalidArgument);
  // The same client claiming again (a reloaded page) gets a fresh lease.
  auto a = lease.Claim("page", false);
  auto b = lease.Claim("page", false);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NE(a->lease, b->lease);
  EXPECT_FALSE(lease.Check(a->lease));
}

TEST(SecretsEqual, ComparesWholeStrings) {
  EXPECT_TRUE(SecretsEqual("abc", "abc"));
  EXPECT_FALSE(SecretsEqual("abc", "abd"));
  EXPECT_FALSE(SecretsEqual("abc", "abcd"));
  EXPECT_FALSE(SecretsEqual("", "a"));
}

TEST(EventHub, ListenersGetEventsInOrderAndMissOnlyWhatFellOutOfTheWindow) {
  EventHub hub(4);
  for (int i = 1; i <= 6; ++i) hub.Publish("progress", {{"i", i}});
  const std::vector<ConsoleEvent> all = hub.WaitAfter(0, 0ms);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all.front().seq, 3u);
  EXPECT_EQ(all.back().data["i"], 6);
  EXPECT_TRUE(hub.WaitAfter(6, 10ms).empty());
  std::thread later([&] {
    std::this_thread::sleep_for(20ms);
    hub.Publish("view", {{"view", 0}});
  });
  const std::vector<ConsoleEvent> woken = hub.WaitAfter(6, 10s);
  later.join();
  ASSERT_EQ(woken.size(), 1u);
  EXPECT_EQ(woken[0].name, "view");
  hub.Close();
  EXPECT_TRUE(hub.WaitAfter(0, 10s).empty());
}

}  // namespace
}  // namespace hairrig
