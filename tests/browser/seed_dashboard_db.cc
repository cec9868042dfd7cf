// seed_dashboard_db DB: a farm database for the dashboard and compare tests, without a farm.
//   nightly-1  suite=nightly  tx2, pi4b x s1, s3 x baseline, enavi x 3 seeds; one episode fails
//   nightly-2  suite=nightly  the same, with planner.v_max 1.5 on tx2/s1/baseline: slower
//                             flights there, the planted regression, and another cost model
//                             digest in their provenance
//   hostile    suite=hostile  a job named <img src=x onerror=alert(1)>
//   oneseed-1  suite=oneseed  tx2 x s1 x baseline, one seed
//   oneseed-2  suite=oneseed  the same with planner.v_max 1.5: slower, but one seed pair cannot
//                             tell it apart from the draw (paired mode: cannot judge)
//   ros-1      suite=ros      tx2 x s1 x a user's ROS stack `myplanner` and enavi x 2 seeds
//   crashes-1  suite=crashes  tx2 x s1 x baseline x 7 seeds: seed 7 collides with 400 deadline
//                             misses (the others 50), so mean ± std of success passes 1 and of
//                             collided and deadline misses 0
//   windy-1    suite=windy    tx2 x s1 x enavi, one seed, in 4 m/s wind with moderate turbulence
//                             and typical odometry noise: the wind_speed and odometry_error columns
// Prints {"base", "candidate", "hostile", "oneseed_base", "oneseed_candidate", "ros", "crashes",
// "windy"} job ids as JSON.
// seed_dashboard_db DB --pending-ros: only ros-1, submitted and never flown (no worker offers ros).
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "server/store/store.h"
#include "tests/support/seed_store.h"
#include "workers/emulation/emulated_nav_link.h"

namespace {

constexpr const char* kNightly = R"(
boards: [tx2, pi4b]
scenarios: [s1, s3]
methods: [baseline, enavi]
seeds: 3
)";

constexpr const char* kFailing = R"(  - match: {board: pi4b, scenario: s3, method: enavi, seed: 2}
    overrides: {fake.exit_code: 3}
)";

// A user's ROS 1 stack as a method (docs/ros.md): the pages name it as they name ours.
constexpr const char* kRos = R"(name: ros-1
labels: {suite: ros}
boards: [tx2]
scenarios: [s1]
methods: [myplanner, enavi]
seeds: 2
clock: emulated
ros_methods:
  myplanner: {run: [rosrun, my_pkg, planner], topics: {command: /cmd}}
)";

}  // namespace

int main(int argc, char** argv) {
  enavi::emulation::RegisterEmulatedLink();  // the clocks enavi's main registers: ros-1 is emulated
  const bool pending_ros = argc == 3 && std::string(argv[2]) == "--pending-ros";
  if (argc != 2 && !pending_ros) {
    std::cerr << "usage: seed_dashboard_db DB [--pending-ros]\n";
    return 2;
  }
  enavi::server::StoreOptions options;
  options.max_attempts = 1;
  enavi::server::Store store(argv[1], options);
  const std::int64_t t0 = 1764547200000;  // 2025-12-01 00:00 UTC; fixed so pages are reproducible
  if (pending_ros) {
    std::cout << nlohmann::json{{"ros", enavi::testing::SubmitJob(store, kRos, t0)}}.dump() << "\n";
    return 0;
  }
  const std::string base = enavi::testing::SeedJob(
      store, std::string("name: nightly-1\nlabels: {suite: nightly, branch: main}\n") + kNightly +
                 "episode_overrides:\n" + kFailing,
      t0);
  const std::string candidate = enavi::testing::SeedJob(
      store, std::string("name: nightly-2\nlabels: {suite: nightly, branch: feature}\n") + kNightly +
                 "episode_overrides:\n" + kFailing +
                 "  - match: {board: tx2, scenario: s1, method: baseline}\n"
                 "    overrides: {planner.v_max: 1.5, fake.cost_model_revision: 2}\n",
      t0 + 86400000);
  const std::string hostile = enavi::testing::SeedJob(
      store, "name: \"<img src=x onerror=alert(1)>\"\nlabels: {suite: hostile}\n"
             "boards: [x86]\nscenarios: [s2]\nmethods: [baseline]\nseeds: 1\n",
      t0 + 2 * 86400000);
  constexpr const char* kOneSeed = "boards: [tx2]\nscenarios: [s1]\nmethods: [baseline]\nseeds: 1\n";
  const std::string oneseed_base = enavi::testing::SeedJob(
      store, std::string("name: oneseed-1\nlabels: {suite: oneseed}\n") + kOneSeed, t0 + 3 * 86400000);
  const std::string oneseed_candidate = enavi::testing::SeedJob(
      store, std::string("name: oneseed-2\nlabels: {suite: oneseed}\n") + kOneSeed +
                 "overrides: {planner.v_max: 1.5}\n",
      t0 + 4 * 86400000);
  const std::string ros = enavi::testing::SeedJob(store, kRos, t0 + 5 * 86400000);
  const std::string crashes = enavi::testing::SeedJob(
      store, "name: crashes-1\nlabels: {suite: crashes}\nboards: [tx2]\nscenarios: [s1]\nmethods: [baseline]\n"
             "seeds: 7\nepisode_overrides:\n  - match: {seed: 7}\n    overrides: {fake.deadline_misses: 400}\n",
      t0 + 6 * 86400000);
  const std::string windy = enavi::testing::SeedJob(
      store, "name: windy-1\nlabels: {suite: windy}\nboards: [tx2]\nscenarios: [s1]\nmethods: [enavi]\nseeds: 1\n"
             "wind: {speed_mps: 4, turbulence: moderate}\nodometry_noise: typical\n",
      t0 + 7 * 86400000);
  std::cout << nlohmann::json{{"base", base},
                              {"candidate", candidate},
                              {"hostile", hostile},
                              {"oneseed_base", oneseed_base},
                              {"oneseed_candidate", oneseed_candidate},
                              {"ros", ros},
                              {"crashes", crashes},
                              {"windy", windy}}
                   .dump()
            << "\n";
  return 0;
}
