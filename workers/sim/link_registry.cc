#include "workers/sim/link_registry.h"

#include <mutex>
#include <stdexcept>

#include "workers/sim/virtual_nav_link.h"

namespace enavi::sim {
namespace {

// The built-in link: the stack in this process on the virtual clock.
LinkInfo VirtualLink() {
  return {kNavstackMethod, "virtual", "sim-time EDF on the board's cores, job costs from the cost model (deterministic)",
          [](const LinkRequest& r) -> std::unique_ptr<NavLink> {
            return std::make_unique<VirtualNavLink>(*r.method, *r.nav, r.threads, r.policy,
                                                    MakeCostModel(*r.spec, *r.board, r.method->cost_family),
                                                    r.initial, r.job_observer);
          },
          ""};
}

// A user's ROS stack flies through the ROS bridge (workers/ros), which registers itself where it
// was built; until then, the reason it cannot.
LinkInfo RosNotBuilt() {
  return {kRosMethod, "emulated", "a user's ROS 1 stack (not built)", nullptr,
          "this enavi was built without the ROS bridge (Debian's ROS packages: scripts/install-deps.sh, then rebuild)"};
}

struct Registry {
  std::mutex mutex;
  std::vector<LinkInfo> links = {VirtualLink(), RosNotBuilt()};
};

Registry& TheRegistry() {
  static Registry registry;
  return registry;
}

// How errors name a kind of method ("... is a ROS stack, and ...").
std::string KindName(const std::string& kind) { return kind == kRosMethod ? "ROS" : kind; }

std::string Join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::string MethodKindOf(const api::EpisodeSpec& spec) { return spec.ros ? kRosMethod : kNavstackMethod; }

void RegisterLink(LinkInfo link) {
  if (link.kind.empty() || link.clock.empty()) throw std::invalid_argument("link: empty kind or clock");
  if (!link.make && link.unavailable.empty())
    throw std::invalid_argument("link " + link.kind + "/" + link.clock + ": no factory");
  Registry& r = TheRegistry();
  std::lock_guard lock(r.mutex);
  for (LinkInfo& l : r.links) {
    if (l.kind == link.kind && l.clock == link.clock) {
      l = std::move(link);
      return;
    }
  }
  r.links.push_back(std::move(link));
}

std::vector<LinkInfo> Links() {
  Registry& r = TheRegistry();
  std::lock_guard lock(r.mutex);
  return r.links;
}

std::optional<LinkInfo> FindLink(const std::string& kind, const std::string& clock) {
  for (LinkInfo& l : Links())
    if (l.kind == kind && l.clock == clock) return std::move(l);
  return std::nullopt;
}

std::string LinkUnavailableReason(const std::string& kind, const std::string& clock) {
  const std::optional<LinkInfo> link = FindLink(kind, clock);
  if (!link) return "no " + kind + " link runs on the " + clock + " clock in this enavi";
  return link->unavailable;
}

std::unique_ptr<NavLink> MakeLink(const LinkRequest& request) {
  const std::string kind = MethodKindOf(*request.spec);
  const std::optional<LinkInfo> link = FindLink(kind, request.spec->clock);
  if (!link) {
    std::vector<std::string> clocks;
    for (const LinkInfo& l : Links())
      if (l.kind == kind) clocks.push_back(l.clock);
    if (kind == kNavstackMethod)
      throw std::invalid_argument("clock: unknown clock '" + request.spec->clock + "' (known: " + Join(clocks) + ")");
    if (clocks.empty())
      throw std::invalid_argument("method: '" + request.spec->method + "' is a " + KindName(kind) +
                                  " stack, and this enavi was built without a link that runs one");
    throw std::invalid_argument("clock: method '" + request.spec->method + "' is a " + KindName(kind) + " stack: it runs on " +
                                Join(clocks) + ", not on '" + request.spec->clock + "'");
  }
  if (!link->unavailable.empty())
    throw std::invalid_argument("method: '" + request.spec->method + "' is a " + KindName(kind) + " stack, and " + link->unavailable);
  return link->make(request);
}

std::vector<ClockInfo> Clocks() {
  std::vector<ClockInfo> clocks;
  for (const LinkInfo& l : Links())
    if (l.kind == kNavstackMethod) clocks.push_back({l.clock, l.summary});
  return clocks;
}

}  // namespace enavi::sim
