#include "python/nav_env_core.h"

#include <stdexcept>

#include "python/env_core.h"

namespace enavi::python {
NavEnvCore::NavEnvCore(NavEnvConfig config) : config_(std::move(config)) {
  CheckBoard(config_.board);
  if (config_.decimation < 1 || config_.decimation > 10 || 640 % config_.decimation || 480 % config_.decimation)
    throw std::invalid_argument("image: the 640x480 sensor decimated by a whole n in [1, 10] (64x48 at n = 10), got n = " +
                                std::to_string(config_.decimation));
  for (const auto& [name, value] : config_.overrides)
    if (name.rfind("learned.", 0) == 0 || name == "camera.decimation")
      throw std::invalid_argument("overrides: " + name + " is the environment's (image, latency, multiply_adds)");
  width_ = 640 / config_.decimation;
  height_ = 480 / config_.decimation;
  multiply_adds_ = config_.multiply_adds > 0 ? config_.multiply_adds
                                             : navstack::rl::DefaultNavArchitecture(width_, height_).multiply_adds();
}

NavEnvCore::~NavEnvCore() = default;

NavTransition NavEnvCore::Reset(std::uint64_t seed) {
  stepper_.reset();
  api::EpisodeSpec spec =
      EnvEpisodeSpec("learned", config_.world, config_.world_params, config_.board, config_.timeout_s, seed);
  spec.overrides = config_.overrides;
  spec.overrides["camera.decimation"] = config_.decimation;
  spec.overrides["learned.zero_latency"] = config_.zero_latency ? 1 : 0;
  spec.overrides["learned.multiply_adds"] = config_.zero_latency ? 0 : static_cast<double>(multiply_adds_);
  world_ = sim::PrepareSpecWorld(spec);
  stepper_ = std::make_unique<sim::NavStepper>(spec, *world_);
  return stepper_->First();
}

NavTransition NavEnvCore::Step(const Eigen::VectorXd& action) {
  if (!stepper_) throw std::logic_error("step() before reset() or after the episode ended");
  return stepper_->Step(action);
}

}  // namespace enavi::python
