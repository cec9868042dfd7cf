#pragma once
// Job specs: a matrix of boards x scenarios x methods x seeds in YAML, validated and expanded
// deterministically into EpisodeSpecs (docs/design.md, "One episode"; docs/farm.md).
//
//   name: tx2-city                # optional; default: the file's stem
//   boards: [tx2, pi4b]           # the registered boards (`enavi fly --help` lists them)
//   scenarios:                    # registered scenario ids, or a world file under an allowed root
//     - s1
//     - worlds/hall.yaml
//     - {world: meshes/yard.obj, start: [0, 0, 1], goal: [30, 0, 1], params: {k: v}}
//     - {world: meshes/block.glb, units: mm, up: z, recenter: true, start: [0, 0, 5], goal: [40, 0, 5]}
//     - {world: gazebo/yard.world, model_path: [gazebo/models], start: [0, 0, 2], goal: [20, 0, 2]}
//   methods: [baseline, fixed, enavi]  # the registered methods, and the job's ROS methods
//   ros_methods:                  # users' ROS 1 stacks as methods (api/ros_stack.h, docs/ros.md)
//     ego: stacks/ego.yaml        # a stack file under an allowed root, or the stack inline:
//     mine: {launch: launch/mine.launch, topics: {command: /cmd}}
//   rosbag: bags                  # ROS methods: record each episode's topics into a bag there
//   seeds: 3                      # a count (1..N) or a list [1, 7, 9]
//   clock: virtual                # a registered clock: virtual | emulated
//   cost: model                   # model | measured
//   dilation: 1.0                 # emulated clock only: 1 sim s = dilation wall s, or auto
//   speed_probe: check            # emulated clock only: check | use | off (api/episode.h)
//   timeout_s: 0                  # 0: derived from the start-goal distance
//   wind:                         # the air (api/episode.h; default still): mean wind, gust, turbulence
//     {speed_mps: 4, direction_deg: 90, turbulence: moderate,
//      gust: {speed_mps: 6, direction_deg: 0, start_s: 10, rise_s: 1.5, hold_s: 2}}
//   odometry_noise: typical       # what the stack is told of its state: none | good | typical | poor
//   policy: policies/enavi.json   # E-Navi policy file under an allowed root; default: shipped
//   world_params: {density: "0.3"}
//   overrides: {planner.v_max: 1.5}  # tunables of every listed method, checked here
//   labels: {branch: main, suite: nightly}   # free key/value tags, queryable (see LabelError)
//   episode_overrides:            # later entries win
//     - match: {board: tx2, method: [enavi], scenario: s1, seed: 2}
//       timeout_s: 120
//       overrides: {strategy.f_adapt: 10}
//   collect: rollouts             # RL collection job: each episode's rollout is stored too
//   sample: true                  # collection: sample the policy's actions (false: greedy)
//
// Instead of the boards x scenarios x seeds matrix, `episodes:` may list the episodes one by one
// (each is flown with every method): [{board: tx2, scenario: s1, seed: 104}, ...].
// A collection job needs one method, [enavi] (its frequency policy's decisions) or [learned] (a
// nav policy's velocity commands and depth images), the virtual clock and a policy: a file, or
// `sha256:HEX` for a policy uploaded to the server (POST /api/policies).

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "api/episode.h"

namespace enavi::api {

/// A job expands to at most this many episodes.
inline constexpr std::size_t kMaxJobEpisodes = 10000;
/// `seeds: N` accepts 1..kMaxSeedCount; a seed list holds at most that many entries.
inline constexpr std::int64_t kMaxSeedCount = 1000;
/// Largest episode timeout a job may ask for (seconds of simulated time).
inline constexpr double kMaxTimeoutS = 3600.0;
/// Largest emulated-clock dilation (1 sim second = dilation wall seconds).
inline constexpr double kMaxDilation = 100.0;
/// `dilation: auto`: the smallest multiple of 0.25 at which the board fits the host's free CPUs
/// when the episode starts (what `enavi fly --clock emulated` does without --dilation).
inline constexpr double kAutoDilation = 0.0;
/// A job carries at most this many labels.
inline constexpr std::size_t kMaxLabels = 32;

/// Bad job spec: the message reads "FILE:LINE: field: reason".
class JobSpecError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
  /// "SOURCE:LINE: FIELD: REASON", its parts kept so that a caller that wrote the YAML itself
  /// (`enavi eval` from its flags) can name what its user typed instead.
  JobSpecError(const std::string& source, int line, std::string field, std::string reason)
      : std::invalid_argument(source + ":" + std::to_string(line) + ": " + field + ": " + reason),
        field_(std::move(field)), reason_(std::move(reason)) {}
  const std::string& field() const { return field_; }  ///< empty when the message has no parts
  const std::string& reason() const { return reason_; }

 private:
  std::string field_, reason_;
};

struct JobSpecOptions {
  /// World and policy files must resolve inside one of these; relative paths in the spec are
  /// taken relative to the first. Empty: the current directory.
  std::vector<std::filesystem::path> allowed_roots;
  std::size_t max_episodes = kMaxJobEpisodes;
  /// The registries' contents: methods and their tunables, boards, scenarios and clocks. Every
  /// name and override in a spec is checked against it. Required.
  Catalog catalog;
};

struct ScenarioEntry {
  std::string world;  ///< scenario id, or the canonical path of a world file
  std::optional<Vec3> start, goal;
  std::map<std::string, std::string> params;
  std::string units, up;  ///< mesh files: placement (EpisodeSpec::units, up, scale, recenter)
  double scale = 1.0;
  bool recenter = false;
  std::vector<std::string> model_path;  ///< SDF worlds: canonical model directories
};

/// Settings applied to the episodes a `match` selects (empty match lists: any).
struct EpisodeOverride {
  std::vector<std::string> boards, scenarios, methods;
  std::vector<std::uint64_t> seeds;
  std::optional<double> timeout_s, dilation;
  std::optional<std::string> policy;
  std::map<std::string, double> overrides;
  std::map<std::string, std::string> world_params;
};

/// One episode of an explicit `episodes:` list.
struct EpisodePick {
  std::string board;
  ScenarioEntry scenario;
  std::uint64_t seed = 1;
};

/// What a collection job (`collect: rollouts`) asks for.
struct CollectSpec {
  bool sample = false;  ///< sample the policy's actions (training); false: greedy
};

/// Prefix of a policy named by content hash instead of a file: "sha256:" + 64 hex digits.
inline constexpr const char* kPolicyHashPrefix = "sha256:";
/// True for "sha256:" followed by 64 lower-case hex digits.
bool IsPolicyHashRef(const std::string& policy);

struct JobSpec {
  std::string name;
  std::vector<std::string> boards;
  std::vector<ScenarioEntry> scenarios;
  std::vector<std::string> methods;
  std::vector<std::uint64_t> seeds;
  std::string clock = "virtual";
  std::string cost = "model";
  double dilation = 1.0;
  std::string speed_probe = "check";
  double timeout_s = 0.0;
  std::string policy;
  std::map<std::string, std::string> world_params;
  std::map<std::string, double> overrides;
  std::vector<EpisodeOverride> episode_overrides;
  std::vector<EpisodePick> episodes;  ///< explicit list instead of the matrix (when non-empty)
  std::optional<CollectSpec> collect;
  std::map<std::string, std::string> labels;  ///< free tags (branch, commit, suite, ...)
  /// The job's ROS methods by name (each also listed in `methods`).
  std::map<std::string, RosStack> ros_methods;
  std::string rosbag_dir;  ///< canonical directory for the ROS episodes' bags; empty: none
  WindSpec wind;  ///< every episode's air
  std::string odometry_noise = "none";  ///< every episode's odometry preset

  std::size_t MatrixSize() const {
    if (!episodes.empty()) return episodes.size() * methods.size();
    return boards.size() * scenarios.size() * methods.size() * seeds.size();
  }
};

/// Parses and validates a job spec; `file_name` is used in error messages.
/// @throws JobSpecError "FILE:LINE: field: reason" on any bad input.
JobSpec ParseJobSpec(const std::string& yaml_text, const std::string& file_name,
                     const JobSpecOptions& options = {});

/// Reads `path` and parses it (relative world paths still resolve against the allowed roots).
JobSpec LoadJobSpec(const std::filesystem::path& path, const JobSpecOptions& options = {});

/// The episodes of a job, in a fixed order: boards, then scenarios, then methods, then seeds,
/// each in the order the spec lists them. Same spec -> same list.
std::vector<EpisodeSpec> ExpandJob(const JobSpec& job);

/// Why `key: value` is not a valid label, or "" when it is. Keys: 1..63 characters of
/// [a-z0-9_.-], starting with a letter or digit; values: 1..128 characters of [A-Za-z0-9_.:/@+-].
/// The charset keeps labels safe in URLs, shell commands and HTML without quoting surprises.
std::string LabelError(const std::string& key, const std::string& value);

/// Parses a "key=value" label filter (`enavi status --label`, `GET /api/jobs?label=`).
/// @throws std::invalid_argument naming `field` and the reason.
std::pair<std::string, std::string> ParseLabelFilter(const std::string& text,
                                                     const std::string& field);

}  // namespace enavi::api
