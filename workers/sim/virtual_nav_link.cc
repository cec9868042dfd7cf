#include "workers/sim/virtual_nav_link.h"

namespace enavi::sim {

VirtualNavLink::VirtualNavLink(const navstack::MethodInfo& method, const navstack::NavStackOptions& options,
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
