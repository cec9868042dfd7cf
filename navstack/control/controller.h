#pragma once
// The flight controller the episode runner calls at 200 Hz: SE(3) tracking + motor mixer.

#include "navstack/common/state.h"
#include "navstack/control/geometric_controller.h"
#include "navstack/control/mixer.h"
#include "navstack/control/vehicle.h"

namespace enavi::navstack {

/// Geometric tracking controller (GeometricController) followed by the motor mixer (Mixer):
/// state + trajectory sample -> rotor speed commands. Call Update() at options.rate_hz
/// (200 Hz by default) and hold the command in between.
class Controller {
 public:
  /// @throws std::invalid_argument on bad vehicle parameters or options.
  explicit Controller(const VehicleParams& vehicle = {},
                      const GeometricControllerOptions& options = {});

  /// One control step: rotor speeds, rad/s, in the order of VehicleParams::RotorPositions().
  RotorCommand Update(const VehicleState& state, const TrajectorySample& reference);

  /// Clears the controller's integral state.
  void Reset();

  /// Diagnostics of the last Update().
  const ControlOutput& last_output() const { return last_output_; }
  const MixResult& last_mix() const { return last_mix_; }

  const GeometricController& tracking() const { return tracking_; }
  const Mixer& mixer() const { return mixer_; }
  double period() const { return 1.0 / tracking_.options().rate_hz; }

 private:
  GeometricController tracking_;
  Mixer mixer_;
  ControlOutput last_output_;
  MixResult last_mix_;
};

}  // namespace enavi::navstack
