// The ways a flight ends, checked in this order after every step: a new one is one more entry.
#include "workers/sim/episode.h"

namespace enavi::sim {

std::vector<EndCondition> EndConditions() {
  return {
      {"goal_reached",
       [](const EpisodeModel& m, const StepView& s, const QuadrotorSim&) -> std::optional<EpisodeEnd> {
         if ((s.vehicle.p_WB - m.world->world.goal).norm() >= m.options.goal_radius) return std::nullopt;
         EpisodeEnd end{.reason = "goal_reached"};
         end.success = true;
         return end;
       }},
      // Any contact with the world (QuadrotorSim::contact, the first touch).
      {"collision",
       [](const EpisodeModel&, const StepView&, const QuadrotorSim& quad) -> std::optional<EpisodeEnd> {
         const std::optional<ContactEvent> contact = quad.contact();
         if (!contact) return std::nullopt;
         EpisodeEnd end{.reason = "collision"};
         end.collided = true;
         end.contact = contact;
         return end;
       }},
      {"timeout",
       [](const EpisodeModel& m, const StepView& s, const QuadrotorSim&) -> std::optional<EpisodeEnd> {
         if (s.t < m.timeout_s) return std::nullopt;
         EpisodeEnd end{.reason = "timeout"};
         end.timed_out = true;
         return end;
       }},
  };
}

}  // namespace enavi::sim
