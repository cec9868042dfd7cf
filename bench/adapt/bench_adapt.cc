// Decision cost of the E-Navi frequency adapter (goal: <= 20 us per decision incl. masking) and of
// its training pieces. Counters: macs = multiply-adds per decision (WorkUnit::kPolicyFlop),
// flops = 2 x macs + tanh evaluations.

#include <benchmark/benchmark.h>

#include <vector>

#include "navstack/adapt/frequency_constraints.h"
#include "navstack/adapt/policy_state.h"
#include "navstack/rl/frequency_adapter.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/ppo.h"

#include "tests/unit/rl/adapter_inputs.h"

namespace enavi::navstack::rl {
namespace {

using testing::ExampleBoard;
using testing::ExampleFlight;

void SetCounters(benchmark::State& state, const ActorCritic& net, bool with_value,
                 std::int64_t extra_macs) {
  const std::int64_t macs = net.MacsPerDecision(with_value) + extra_macs;
  const std::int64_t acts = net.actor().ActivationsPerSample() +
                            (with_value ? net.critic().ActivationsPerSample() : 0);
  state.counters["macs"] = static_cast<double>(macs);
  state.counters["flops"] = static_cast<double>(2 * macs + acts);
}

// The deployed path: actor forward + masked argmax, mask given.
void BM_PolicyGreedyForward(benchmark::State& state) {
  const PolicyFile p = MakeFrequencyPolicy(ActionGrid(), 1);
  ActorCritic::Workspace ws = p.net.MakeWorkspace();
  const FeasibleSet fs = ComputeFeasibleSet(*p.action_grid, ExampleBoard());
  const Eigen::VectorXd obs = Eigen::VectorXd::Constant(kPolicyStateDim, 0.3);
  for (auto _ : state) {
    const PolicyOutput out = p.net.Act(obs, fs.mask, ActMode::kGreedy, nullptr, &ws, false, false);
    benchmark::DoNotOptimize(out.action);
  }
  SetCounters(state, p.net, false, 0);
}
BENCHMARK(BM_PolicyGreedyForward);

// One full flight decision: constraint status, policy state, C1-C4 mask over 189 actions, actor,
// masked argmax. This is the figure to compare with the 20 us goal.
void BM_FrequencyAdapterDecideGreedy(benchmark::State& state) {
  FrequencyAdapter fa(MakeFrequencyPolicy(ActionGrid(), 1));
  const ConstraintInputs c = ExampleBoard();
  const FlightContext f = ExampleFlight();
  for (auto _ : state) {
    const FrequencyDecision d = fa.Decide(c, f, ActMode::kGreedy);
    benchmark::DoNotOptimize(d.action);
  }
  SetCounters(state, fa.policy().net, false,
              FrequencyAdapter::kMaskMacsPerAction * fa.grid().size());
}
BENCHMARK(BM_FrequencyAdapterDecideGreedy);

// A training-rollout decision: sampling, log-prob and the critic's value, recorded.
void BM_FrequencyAdapterDecideSampleRecord(benchmark::State& state) {
  FrequencyAdapter fa(MakeFrequencyPolicy(ActionGrid(), 1));
  const ConstraintInputs c = ExampleBoard();
  const FlightContext f = ExampleFlight();
  Rng rng(1);
  RolloutStep step;
  for (auto _ : state) {
    const FrequencyDecision d = fa.Decide(c, f, ActMode::kSample, &rng, nullptr, &step);
    benchmark::DoNotOptimize(d.action);
  }
  SetCounters(state, fa.policy().net, true,
              FrequencyAdapter::kMaskMacsPerAction * fa.grid().size());
}
BENCHMARK(BM_FrequencyAdapterDecideSampleRecord);

void BM_FeasibleSet(benchmark::State& state) {
  const ActionGrid grid;
  const ConstraintInputs c = ExampleBoard();
  for (auto _ : state) {
    const FeasibleSet fs = ComputeFeasibleSet(grid, c);
    benchmark::DoNotOptimize(fs.num_feasible);
  }
}
BENCHMARK(BM_FeasibleSet);

// PPO loss + gradient of one minibatch of 64 on the paper-sized networks.
void BM_PpoMinibatchGradient(benchmark::State& state) {
  const PolicyFile p = MakeFrequencyPolicy(ActionGrid(), 1);
  const int n = 64;
  PpoBatch b;
  b.num_actions = p.net.num_actions();
  b.obs = Eigen::MatrixXd::Constant(kPolicyStateDim, n, 0.3);
  b.actions.assign(n, 5);
  b.masks.assign(static_cast<std::size_t>(n * b.num_actions), 1);
  b.old_log_probs = Eigen::VectorXd::Constant(n, -5.2);
  b.advantages = Eigen::VectorXd::LinSpaced(n, -1, 1);
  b.returns = Eigen::VectorXd::Constant(n, 0.5);
  PpoGradients g;
  for (auto _ : state) {
    const PpoLossTerms t = ComputePpoLoss(p.net, b, PpoOptions{}, &g);
    benchmark::DoNotOptimize(t.total);
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_PpoMinibatchGradient);

}  // namespace
}  // namespace enavi::navstack::rl

BENCHMARK_MAIN();
