#pragma once
// The registries as the command line shows them: one line per board, scenario or clock for a
// flag's help, read from the registry itself (workers/board/profiles, the worlds generators,
// sim::Clocks()), so a new entry appears in every help text without retyping.

#include <string>
#include <vector>

namespace enavi::cli {

/// "\n    ID: description" for every registered board, scenario or clock.
std::string BoardsHelp();
std::string ScenariosHelp();
std::string ClocksHelp();

/// "a, b, c".
std::string JoinNames(const std::vector<std::string>& names, const char* separator = ", ");

}  // namespace enavi::cli
