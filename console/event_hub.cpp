#include "console/event_hub.h"

namespace hairrig {

uint64_t EventHub::Publish(std::string name, nlohmann::json data) {
  std::lock_guard<std::mutex> lock(mutex_);
  events_.push_back({++last_seq_, std::move(name), std::move(data)});
  while (events_.size() > capacity_) events_.pop_front();
  changed_.notify_all();
  return last_seq_;
}

std::vector<ConsoleEvent> EventHub::WaitAfter(uint64_t after, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return closed_ || last_seq_ > after; });
  std::vector<ConsoleEvent> out;
  if (closed_) return out;
  for (const ConsoleEvent& e : events_) {
    if (e.seq > after) out.push_back(e);
  }
  return out;
}

uint64_t EventHub::last_seq() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_seq_;
}

void EventHub::Close() {
  std::lock_guard<std::mutex> lock(mutex_);
  closed_ = true;
  changed_.notify_all();
}

bool EventHub::closed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return closed_;
}

}  // namespace hairrig
