#pragma once
// The virtual clock's link: the stack in this process on a VirtualExecutor (sim-time global EDF
// over the board's cores, cost model pricing every job).

#include <memory>
#include <string>

#include "api/episode.h"
#include "navstack/methods/method.h"
#include "navstack/runtime/cost_model.h"
#include "navstack/runtime/virtual_executor.h"
#include "workers/board/board_profile.h"
#include "workers/sim/nav_link.h"

namespace enavi::sim {

/// The spec's cost mode on `board`: the cost model at the prices of `cost_family`, or measured
/// host CPU scaled by the board's speed. @throws std::invalid_argument for an unknown mode.
std::unique_ptr<navstack::CostModel> MakeCostModel(const api::EpisodeSpec& spec, const board::BoardProfile& board,
                                                   const std::string& cost_family);

class VirtualNavLink final : public NavLink {
 public:
  VirtualNavLink(const navstack::MethodInfo& method, const navstack::MethodOptions& options, int threads,
                 navstack::SchedulingPolicy policy,
                 std::unique_ptr<navstack::CostModel> cost, const navstack::VehicleState& initial,
                 navstack::JobObserver observer = {});

  void OnState(const navstack::VehicleState& state) override { nav_->OnState(state); }
  void OnFrame(navstack::DepthFramePtr frame) override { nav_->OnFrame(std::move(frame)); }
  void AdvanceTo(double t) override { executor_.AdvanceTo(t); }
  bool paused() const override { return executor_.paused(); }
  navstack::TrajectorySample Reference(double t) override { return nav_->Reference(t); }
  std::vector<navstack::NavEvent> TakeEvents() override { return nav_->TakeEvents(); }
  navstack::TaskRates rates() const override { return nav_->rates(); }
  double map_resolution() const override { return nav_->map_resolution(); }
  NavAccounting Accounting() const override;
  void FinishEpisode(bool collided, bool reached_goal) override { nav_->FinishEpisode(collided, reached_goal); }
  const navstack::rl::Rollout* rollout() const override { return nav_->rollout(); }
  double OffBoardSeconds(navstack::TaskId task, const navstack::WorkCounts& work, double host_cpu_s) const override {
    return cost_->JobSeconds(task, work, host_cpu_s);
  }

 private:
  std::unique_ptr<navstack::CostModel> cost_;
  navstack::VirtualExecutor executor_;
  std::unique_ptr<navstack::Navigator> nav_;
};

}  // namespace enavi::sim
