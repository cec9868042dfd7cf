#include "navstack/control/controller.h"

namespace enavi::navstack {

Controller::Controller(const VehicleParams& vehicle, const GeometricControllerOptions& options)
    : tracking_(vehicle, options), mixer_(vehicle) {}

RotorCommand Controller::Update(const VehicleState& state, const TrajectorySample& reference) {
  last_output_ = tracking_.Compute(state, reference);
  last_mix_ = mixer_.Mix(last_output_.wrench);
  return last_mix_.command;
}

void Controller::Reset() {
  tracking_.Reset();
  last_output_ = {};
  last_mix_ = {};
}

}  // namespace enavi::navstack
