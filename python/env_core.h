#pragma once
// E-Navi's frequency-adaptation problem as a step-by-step environment: each step is one decision
// of the Strategy Controller (paper Sec. V) in a real virtual-clock flight episode. The
// environment steps the episode (sim::Episode) itself, in the caller's thread: a sampled decision
// waits in a DecisionPort (navstack/rl/decision_port.h) with the episode stopped at its instant,
// and the action supplied continues it as if it had been chosen there. Rewards are the rollout's
// the stack records.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "navstack/rl/decision_port.h"
#include "navstack/rl/rollout.h"
#include "workers/sim/episode.h"

namespace enavi::python {

struct EnvConfig {
  std::string world = "empty";  ///< any world the CLI accepts (a scenario id or a file)
  std::string board = "tx2";
  std::string policy;           ///< critic/actor file the stack loads; empty: the shipped one
  double timeout_s = 0;         ///< 0: derived from the start-goal distance
  std::map<std::string, std::string> world_params;
  std::map<std::string, double> overrides;
};

/// What reset() and step() return.
struct Transition {
  Eigen::VectorXd obs;
  std::vector<std::uint8_t> mask;  ///< feasible actions of the decision at `obs`
  double reward = 0;
  bool terminated = false;  ///< goal reached or collision
  bool truncated = false;   ///< the episode ended otherwise (time-out, fail-safe)
  std::map<std::string, double> metrics;  ///< at the end: success, collided, flight_time_s, ...
  std::string end_reason;
  double t = 0;             ///< decision index
};

/// The environments' common checks and pieces.
/// @throws std::invalid_argument "board: unknown board '...' (known: ...)".
void CheckBoard(const std::string& board);
/// An environment's episode: `method` in `world` (with its generator parameters) on `board`,
/// virtual clock, world and episode seed `seed`.
api::EpisodeSpec EnvEpisodeSpec(const std::string& method, const std::string& world,
                                const std::map<std::string, std::string>& world_params, const std::string& board,
                                double timeout_s, std::uint64_t seed);

class EnvCore {
 public:
  /// @throws std::invalid_argument for an unknown board, or strategy.explore among the overrides.
  explicit EnvCore(EnvConfig config);
  ~EnvCore();
  EnvCore(const EnvCore&) = delete;
  EnvCore& operator=(const EnvCore&) = delete;

  /// Starts a new episode (world and episode seed `seed`), abandoning one in progress; returns
  /// its first decision.
  /// @throws std::invalid_argument for a bad world or overrides, std::runtime_error when the
  ///   episode ends before its first decision.
  Transition Reset(std::uint64_t seed);
  /// Takes `action` for the pending decision; returns the next decision or the episode's end.
  /// @throws std::invalid_argument for an infeasible action, std::logic_error without reset().
  Transition Step(int action);

  int obs_size() const;
  int action_size() const;

 private:
  /// Steps the episode to its next decision or its end.
  Transition Advance();

  EnvConfig config_;
  // One episode: its world, the port its decisions wait in, its rollout (rewards), the episode.
  std::shared_ptr<const sim::PreparedWorld> world_;
  std::unique_ptr<navstack::rl::DecisionPort> decisions_;
  std::unique_ptr<navstack::rl::Rollout> rollout_;
  std::unique_ptr<sim::Episode> episode_;
  Eigen::VectorXd last_obs_;
  bool finished_ = true;
};

}  // namespace enavi::python
