// api/ cannot see the registries above it (boards in workers/board, scenarios in worlds), so job
// validation keeps their names as data (api::kBoards, api::kScenarios). These tests fail the
// moment a registry and its copy disagree.
#include <algorithm>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "api/episode.h"
#include "api/job_spec.h"
#include "workers/board/board_profile.h"
#include "worlds/generators.h"

namespace enavi {
namespace {

template <typename C>
std::set<std::string> AsSet(const C& names) {
  return std::set<std::string>(names.begin(), names.end());
}

TEST(CatalogAgreementTest, JobBoardsAreTheEmbeddedBoardProfiles) {
  EXPECT_EQ(AsSet(api::kBoards), AsSet(board::KnownBoards()));
}

TEST(CatalogAgreementTest, JobScenariosAreTheWorldGenerators) {
  std::set<std::string> generators;
  for (const worlds::GeneratorInfo& g : worlds::Generators()) generators.insert(g.id);
  EXPECT_EQ(AsSet(api::kScenarios), generators);
}

}  // namespace
}  // namespace enavi
