// The link registry (workers/sim/link_registry.h): a link is found by method kind and clock, the
// farm's clocks are those the registered navstack links run on, and a spec asking for a link that
// is not there (an unknown clock, a ROS stack without the bridge, a ROS stack on another clock)
// fails naming why.
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "workers/sim/link_registry.h"

namespace enavi::sim {
namespace {

std::string MakeLinkError(const api::EpisodeSpec& spec) {
  LinkRequest request;
  request.spec = &spec;
  try {
    MakeLink(request);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "built";
}

api::EpisodeSpec RosSpec(const std::string& clock) {
  api::EpisodeSpec spec;
  spec.method = "ego";
  spec.ros = api::RosStack{};
  spec.ros->name = "ego";
  spec.clock = clock;
  return spec;
}

TEST(LinkRegistryTest, TheVirtualClockIsBuiltInAndARegisteredLinkAddsItsClock) {
  ASSERT_FALSE(Clocks().empty());
  EXPECT_EQ(Clocks().front().name, "virtual");
  EXPECT_EQ(LinkUnavailableReason(kNavstackMethod, "virtual"), "");

  int built = 0;
  RegisterLink({kNavstackMethod, "stepped", "a test clock", [&built](const LinkRequest& r) -> std::unique_ptr<NavLink> {
                  EXPECT_EQ(r.spec->clock, "stepped");
                  ++built;
                  return nullptr;
                },
                ""});
  EXPECT_EQ(Clocks().back().name, "stepped");
  EXPECT_EQ(Clocks().back().summary, "a test clock");
  api::EpisodeSpec spec;
  spec.clock = "stepped";
  EXPECT_EQ(MakeLinkError(spec), "built");
  EXPECT_EQ(built, 1);
}

TEST(LinkRegistryTest, WhatIsNotRegisteredIsRefusedNamingWhy) {
  api::EpisodeSpec spec;
  spec.clock = "wall";
  EXPECT_EQ(MakeLinkError(spec).rfind("clock: unknown clock 'wall' (known: virtual", 0), 0u) << MakeLinkError(spec);
  EXPECT_EQ(MakeLinkError(RosSpec("emulated")),
            "method: 'ego' is a ROS stack, and this enavi was built without the ROS bridge (Debian's ROS packages: "
            "scripts/install-deps.sh, then rebuild)");
  EXPECT_NE(LinkUnavailableReason(kRosMethod, "emulated"), "");
  EXPECT_EQ(MakeLinkError(RosSpec("virtual")), "clock: method 'ego' is a ROS stack: it runs on emulated, not on 'virtual'");
  EXPECT_THROW(RegisterLink({kNavstackMethod, "nowhere", "", nullptr, ""}), std::invalid_argument)
      << "a link without a factory must say why it cannot run";
}

}  // namespace
}  // namespace enavi::sim
