// Open/Close/HealthCheck for devices with no connection to manage (the
// simulated and replayed backends): Open always finds the unit, HealthCheck
// passes while it is open.
#pragma once

#include "drivers/device.h"

namespace hairrig {

template <typename Base>
class AlwaysPresentDevice : public Base {
 public:
  using Base::Base;
  Status Open() override {
    this->SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status Close() override {
    this->SetState(DeviceState::kClosed);
    return Status::Ok();
  }
  Status HealthCheck() override {
    return this->RequireState({DeviceState::kReady, DeviceState::kBusy}, "HealthCheck");
  }
};

}  // namespace hairrig
