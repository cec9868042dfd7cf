#include "workers/sim/virtual_nav_link.h"

#include <stdexcept>

namespace enavi::sim {

std::unique_ptr<navstack::CostModel> MakeCostModel(const api::EpisodeSpec& spec, const board::BoardProfile& board,
                                                   const std::string& cost_family) {
  if (spec.cost == "model")
    return std::make_unique<navstack::WorkCountCostModel>(
        board::BoardCoefficients(board, board::LoadReferenceCosts(), cost_family));
  if (spec.cost == "measured") return std::make_unique<navstack::MeasuredCostModel>(1.0 / board.per_core_speed);
  throw std::invalid_argument("cost: unknown cost mode '" + spec.cost + "' (known: model, measured)");
}

VirtualNavLink::VirtualNavLink(const navstack::MethodInfo& method, const navstack::MethodOptions& options,
                               int threads, navstack::SchedulingPolicy policy,
                               std::unique_ptr<navstack::CostModel> cost, const navstack::VehicleState& initial,
                               navstack::JobObserver observer)
    : cost_(std::move(cost)), executor_(threads, *cost_, policy), nav_(method.make(options, &executor_, initial)) {
  if (observer) executor_.SetJobObserver(std::move(observer));
}

NavAccounting VirtualNavLink::Accounting() const {
  NavAccounting a;
  for (int i = 0; i < navstack::kTaskCount; ++i) a.tasks[i] = executor_.stats(static_cast<navstack::TaskId>(i));
  a.plan_failures = nav_->plan_failures();
  a.notes["cost"] = cost_->mode();
  return a;
}

}  // namespace enavi::sim
