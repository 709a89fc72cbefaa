#include "rig/capture_control.h"

namespace hairrig {

void CaptureControl::Request(Kind kind, const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (handler_) {
    handler_(kind, reason);
    return;
  }
  if (!pending_kind_ || kind == Kind::kEmergency) {
    pending_kind_ = kind;
    pending_reason_ = reason;
  }
}

void CaptureControl::Attach(Handler handler) {
  std::lock_guard<std::mutex> lock(mutex_);
  handler_ = std::move(handler);
  if (handler_ && pending_kind_) {
    handler_(*pending_kind_, pending_reason_);
    pending_kind_.reset();
  }
}

void CaptureControl::Detach() {
  std::lock_guard<std::mutex> lock(mutex_);
  handler_ = nullptr;
}

}  // namespace hairrig
