// One controlling client at a time (docs/design.md section 9): the console's other
// clients read only. A client claims control and gets a lease, a random token
// it sends with every request that changes the rig; the lease lapses when its
// holder goes quiet (a closed browser never locks the rig), and another client
// may take control explicitly. Thread-safe.
#pragma once

#include <chrono>
#include <mutex>
#include <optional>
#include <string>

#include "core/status.h"

namespace hairrig {

class ControlLease {
 public:
  using Clock = std::chrono::steady_clock;

  // A lease lapses `ttl` after the last Claim or Check that named it.
  explicit ControlLease(std::chrono::milliseconds ttl = std::chrono::seconds(15)) : ttl_(ttl) {}

  struct Grant {
    std::string lease;  // 32 hex digits
    std::string holder;
  };
  // Control for `client` (1-64 printable ASCII characters, else
  // InvalidArgument). FailedPrecondition naming the holder when another
  // client's lease is live and `take` is false; a client claiming again
  // (a reloaded page) gets a new lease.
  Result<Grant> Claim(const std::string& client, bool take, Clock::time_point now = Clock::now());
  // True when `lease` is the live lease; it then lives `ttl` from `now`.
  bool Check(const std::string& lease, Clock::time_point now = Clock::now());
  // Ends `lease` if it is the live one; false otherwise.
  bool Release(const std::string& lease);
  // Who holds a live lease.
  std::optional<std::string> Holder(Clock::time_point now = Clock::now()) const;
  std::chrono::milliseconds ttl() const { return ttl_; }

 private:
  bool LiveLocked(Clock::time_point now) const;

  const std::chrono::milliseconds ttl_;
  mutable std::mutex mutex_;
  std::string lease_;  // empty: nobody
  std::string holder_;
  Clock::time_point expires_{};
};

// True when `a` and `b` are equal, in a time that does not depend on where
// they first differ (tokens and leases are compared with it).
bool SecretsEqual(const std::string& a, const std::string& b);

// 32 hex digits from the system's random source.
std::string RandomHexToken();

}  // namespace hairrig
