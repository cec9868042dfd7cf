#include "server/cli/registry_help.h"

#include "workers/board/board_profile.h"
#include "workers/sim/episode.h"
#include "worlds/generators.h"

namespace enavi::cli {
namespace {

std::string Line(const std::string& id, const std::string& text) { return "\n    " + id + ": " + text; }

}  // namespace

std::string BoardsHelp() {
  std::string out;
  for (const std::string& id : board::KnownBoards()) {
    const board::BoardProfile b = board::LoadBoard(id);
    out += Line(id, b.name + "; " + (b.is_host ? std::string("all") : std::to_string(b.cores)) + " cores");
  }
  return out;
}

std::string ScenariosHelp() {
  std::string out;
  for (const worlds::GeneratorInfo& g : worlds::Generators()) out += Line(g.id, g.description);
  return out;
}

std::string ClocksHelp() {
  std::string out;
  for (const sim::ClockInfo& c : sim::Clocks()) out += Line(c.name, c.summary);
  return out;
}

std::string JoinNames(const std::vector<std::string>& names, const char* separator) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : separator) + n;
  return out;
}

}  // namespace enavi::cli
