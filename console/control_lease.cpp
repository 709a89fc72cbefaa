#include "console/control_lease.h"

#include <cstdio>
#include <random>

namespace hairrig {

bool SecretsEqual(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string RandomHexToken() {
  std::random_device source;
  std::string hex;
  for (int i = 0; i < 4; ++i) {
    char part[9];
    std::snprintf(part, sizeof part, "%08x", static_cast<unsigned>(source()));
    hex += part;
  }
  return hex;
}

bool ControlLease::LiveLocked(Clock::time_point now) const {
  return !lease_.empty() && now < expires_;
}

Result<ControlLease::Grant> ControlLease::Claim(const std::string& client, bool take,
                                                Clock::time_point now) {
  if (client.empty() || client.size() > 64)
    return InvalidArgument("client: a name of 1 to 64 characters is required");
  for (const char c : client) {
    if (c < 0x20 || c > 0x7e) return InvalidArgument("client: printable ASCII characters only");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (LiveLocked(now) && holder_ != client && !take) {
    return FailedPrecondition(holder_ + " holds control; take it over explicitly (\"take\": true)");
  }
  lease_ = RandomHexToken();
  holder_ = client;
  expires_ = now + ttl_;
  return Grant{lease_, holder_};
}

bool ControlLease::Check(const std::string& lease, Clock::time_point now) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!LiveLocked(now) || !SecretsEqual(lease, lease_)) return false;
  expires_ = now + ttl_;
  return true;
}

bool ControlLease::Release(const std::string& lease) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (lease_.empty() || !SecretsEqual(lease, lease_)) return false;
  lease_.clear();
  holder_.clear();
  return true;
}

std::optional<std::string> ControlLease::Holder(Clock::time_point now) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!LiveLocked(now)) return std::nullopt;
  return holder_;
}

}  // namespace hairrig
