// Software wiring of trigger lines for backends with no electrical line (the
// simulated and replayed rigs): cameras armed for a line subscribe; a pulse on
// the line calls every subscriber, outside the bus's lock. Thread-safe.
#pragma once

#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace hairrig {

class TriggerBus {
 public:
  // Returns an id for Unsubscribe.
  int Subscribe(const std::string& line, std::function<void()> on_pulse) {
    std::lock_guard<std::mutex> lock(mutex_);
    subscribers_[line][++next_id_] = std::move(on_pulse);
    return next_id_;
  }
  void Unsubscribe(const std::string& line, int id) {
    std::lock_guard<std::mutex> lock(mutex_);
    subscribers_[line].erase(id);
  }
  void Fire(const std::string& line) {
    std::vector<std::function<void()>> calls;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (auto& [id, fn] : subscribers_[line]) calls.push_back(fn);
    }
    for (auto& fn : calls) fn();
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::map<int, std::function<void()>>> subscribers_;
  int next_id_ = 0;
};

}  // namespace hairrig
