#pragma once
// One parser for each kind of value a command line takes, so a flag reads the same in every
// subcommand (`--start`/`--goal`, `--param`/`--set`). Bad values throw std::invalid_argument
// naming the flag and the text (exit 2).

#include <map>
#include <string>
#include <vector>

#include "api/episode.h"

namespace enavi::cli {

/// "x,y,z" in metres: three finite numbers and nothing else.
api::Vec3 ParsePoint(const std::string& flag, const std::string& text);

/// Repeated "name=value" items. A name given twice is refused: neither the first nor the last
/// value can be assumed to be the one meant.
std::map<std::string, std::string> ParseNameValues(const std::string& flag, const std::vector<std::string>& items);

/// The whole of `text` as a finite number, for `flag`'s item `name`.
double ParseNumber(const std::string& flag, const std::string& name, const std::string& text);

}  // namespace enavi::cli
