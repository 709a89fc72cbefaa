// DoOpen/DoClose/DoHealthCheck for devices with no connection to manage (the
// simulated and replayed backends): Open always finds the unit, HealthCheck
// passes while it is open (Device checks that).
#pragma once

#include "drivers/device.h"

namespace hairrig {

template <typename Base>
class AlwaysPresentDevice : public Base {
 public:
  using Base::Base;

 protected:
  Status DoOpen() override {
    this->SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status DoClose() override { return Status::Ok(); }
  Status DoHealthCheck() override { return Status::Ok(); }
};

}  // namespace hairrig
