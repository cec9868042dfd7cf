#include "workers/worker/episode_runner.h"

#include <signal.h>

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "navstack/rl/nav_rollout.h"
#include "navstack/rl/rollout.h"
#include "workers/worker/process.h"

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;

std::string Tail(const fs::path& file, std::size_t max_bytes) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff start = size > static_cast<std::streamoff>(max_bytes)
                                   ? size - static_cast<std::streamoff>(max_bytes)
                                   : 0;
  in.seekg(start);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  return start > 0 ? "..." + text : text;
}

EpisodeOutcome Error(std::string message, double wall_s) {
  EpisodeOutcome out;
  out.kind = EpisodeOutcome::Kind::kError;
  out.error = std::move(message);
  out.wall_time_s = wall_s;
  return out;
}

}  // namespace

std::vector<std::string> DefaultEpisodeCommand() { return {SelfExecutable().string(), "episode"}; }

EpisodeOutcome RunEpisode(const api::EpisodeSpec& spec, const EpisodeRun& run,
                          const std::atomic<bool>& abort) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const fs::path dir = fs::absolute(run.dir);  // the child runs inside it
  fs::create_directories(dir);
  const fs::path spec_file = dir / "spec.json";
  const fs::path result_file = dir / "result.json";
  const fs::path stderr_file = dir / "stderr.log";
  const fs::path rollout_file = dir / "rollout";
  fs::remove(result_file);
  fs::remove(rollout_file);
  {
    std::ofstream out(spec_file, std::ios::binary | std::ios::trunc);
    out << nlohmann::json(spec).dump(2) << "\n";
    if (!out) return Error("cannot write " + spec_file.string(), elapsed());
  }

  SpawnOptions options;
  options.argv = run.command;
  options.argv.insert(options.argv.end(), {"--spec-file", spec_file.string(), "--result-file",
                                           result_file.string()});
  if (run.collect_rollout) options.argv.insert(options.argv.end(), {"--rollout-file", rollout_file.string()});
  options.env = run.env;
  options.cwd = dir;
  options.stdout_file = dir / "stdout.log";
  options.stderr_file = stderr_file;
  options.memory_limit_bytes = run.limits.memory_bytes;
  options.cpu_limit_s = run.limits.cpu_seconds;

  ChildProcess child;
  try {
    child = ChildProcess::Spawn(options);
  } catch (const std::exception& e) {
    return Error(std::string("cannot start the episode: ") + e.what(), elapsed());
  }

  // Wait in short slices so an abort (cancelled job, shutdown) or the timeout acts promptly.
  const auto deadline = start + run.limits.wall_timeout;
  std::optional<ExitStatus> status;
  while (!(status = child.Wait(std::chrono::milliseconds(50)))) {
    if (abort.load()) {
      child.Terminate(std::chrono::seconds(2));
      EpisodeOutcome out;
      out.kind = EpisodeOutcome::Kind::kAborted;
      out.wall_time_s = elapsed();
      return out;
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      child.Terminate(std::chrono::seconds(2));
      return Error("wall-clock timeout after " + std::to_string(run.limits.wall_timeout.count()) +
                       " s; stderr: " + Tail(stderr_file, 1000),
                   elapsed());
    }
  }
  const double wall_s = elapsed();
  if (!status->ok()) {
    std::string reason = "episode command " + status->Describe();
    if (!status->exited && (status->signal == SIGXCPU || status->signal == SIGKILL)) {
      reason += " (CPU limit " + std::to_string(run.limits.cpu_seconds) + " s, or killed)";
    }
    return Error(reason + "; stderr: " + Tail(stderr_file, 2000), wall_s);
  }

  // Exit 0: the result file must hold a full EpisodeResult.
  std::ifstream in(result_file, std::ios::binary);
  if (!in) return Error("episode command exited 0 but wrote no " + result_file.string(), wall_s);
  EpisodeOutcome out;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    out.result = j.get<api::EpisodeResult>();
    // A result without its spec still belongs to this episode.
    if (!j.contains("spec")) out.result.spec = spec;
  } catch (const std::exception& e) {
    return Error("invalid result file " + result_file.string() + ": " + e.what(), wall_s);
  }
  // The rollout goes on in its compact binary form, checked on the way: E-Navi's comes as JSON,
  // the learned method's (depth images) already binary.
  if (run.collect_rollout) {
    std::ifstream rin(rollout_file, std::ios::binary);
    if (!rin) return Error("episode command exited 0 but wrote no " + rollout_file.string(), wall_s);
    const std::string text((std::istreambuf_iterator<char>(rin)), std::istreambuf_iterator<char>());
    try {
      out.rollout = navstack::rl::IsNavRolloutBlob(text)
                        ? text
                        : navstack::rl::EncodeRollout(navstack::rl::DeserializeRollout(text, rollout_file.string()));
      if (navstack::rl::CheckRolloutBlob(out.rollout, rollout_file.string()) == 0)
        return Error("the episode recorded an empty rollout", wall_s);
    } catch (const std::exception& e) {
      return Error(std::string("invalid rollout: ") + e.what(), wall_s);
    }
  }
  out.kind = EpisodeOutcome::Kind::kResult;
  out.wall_time_s = wall_s;
  return out;
}

}  // namespace enavi::worker
