// The console's live events (docs/design.md section 9): what happened, in order,
// for every page and script that listens (GET /api/events, Server-Sent Events).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hairrig {

struct ConsoleEvent {
  uint64_t seq = 0;  // from 1, in publication order
  std::string name;  // "state", "progress", "view", "fault", "capture_end", "processed", "preview"
  nlohmann::json data;
};

// Keeps the newest `capacity` events; a listener that falls further behind
// misses the oldest (each event says its seq, so a gap shows). Thread-safe.
class EventHub {
 public:
  explicit EventHub(size_t capacity = 1024) : capacity_(capacity) {}

  // Returns the event's seq.
  uint64_t Publish(std::string name, nlohmann::json data);
  // Events with seq > `after`, oldest first; waits up to `timeout` for the
  // first one. Empty after the timeout or once Close() was called.
  std::vector<ConsoleEvent> WaitAfter(uint64_t after, std::chrono::milliseconds timeout);
  uint64_t last_seq() const;
  // Wakes every waiter for good (the server is shutting down).
  void Close();
  bool closed() const;

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<ConsoleEvent> events_;
  uint64_t last_seq_ = 0;
  bool closed_ = false;
};

}  // namespace hairrig
