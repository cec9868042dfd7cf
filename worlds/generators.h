#pragma once
// Seeded scenario generators: s1-s5 after the paper's five scenarios, plus `canyon` (street
// canyons, a world the policy was not trained on), `forest` and `empty`, and two with moving
// obstacles (worlds/movers.h): `park-people` (people walking footpaths across s2's park) and
// `street-traffic` (vans driving s4's middle streets), a mover of each crossing the straight
// start-goal line about when the flight gets there. The same (scenario,
// seed, params) gives a byte-identical world file on every machine: std::mt19937_64 raw draws
// mapped to doubles by our own code, only + - * / sqrt and detmath in anything that reaches the
// file, every value rounded to the file precision.
//
// eci range along a baseline flight (docs/results.md, "eci range along a flight"; x86, seeds 1-5,
// version 2) beside the paper's: s1 0.02-0.75 (0.06-0.87), s2 0.07-0.65 (0.08-0.97),
// s3 0.23-0.72 (0.19-0.83), s4 0.07-0.67 (0.26-0.86), s5 0.06-0.51 (0.25-0.79).

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "worlds/world.h"

namespace enavi::worlds {

/// Bumped whenever a generator's output for a given seed changes (adding a generator does not).
inline constexpr int kGeneratorVersion = 2;

/// A tunable generator parameter with its allowed range (inclusive).
struct GeneratorParam {
  std::string name;
  double min = 0.0;
  double max = 0.0;
  double default_value = 0.0;
  std::string help;
};

struct GeneratorInfo {
  std::string id;               ///< the scenario id job specs and `--world` name
  std::string description;
  double paper_path_length = 0;  ///< m, the paper's flight path (0 when not from the paper)
  std::vector<GeneratorParam> params;
  double flight_altitude = 1.5;  ///< m above the ground, of start and goal
};

/// All generators, in a fixed order: the farm's one list of scenarios (job validation, the
/// CLI's help, the paper's matrix of those with a paper path length read it).
const std::vector<GeneratorInfo>& Generators();

/// The generator with this id, or nullptr.
const GeneratorInfo* FindGenerator(std::string_view id);

/// The scenario of a world string as it appears in an episode spec: the generator id, or
/// "custom" for a file.
std::string ScenarioOf(const std::string& world);

/// Generates and validates a world. Start and goal are at the generator's flight altitude (1.5 m
/// above the ground, 5 m for `canyon`), in free space, joined by a route at least 1 m wide, and
/// (except `forest` and `empty`) the straight start-goal line is blocked somewhere. A draw that fails these checks is
/// redrawn from a seed derived deterministically from (seed, attempt).
/// Throws WorldError (file = scenario id) for an unknown scenario, unknown parameter or a value
/// out of range (the message names the parameter and its allowed range).
World Generate(const std::string& scenario, std::uint64_t seed, const std::map<std::string, std::string>& params = {});

}  // namespace enavi::worlds
