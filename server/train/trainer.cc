#include "server/train/trainer.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

#include "api/atomic_file.h"
#include "api/client.h"
#include "api/content_hash.h"
#include "api/job_spec.h"
#include "navstack/adapt/action_grid.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/rollout.h"
#include "server/eval/local_farm.h"
#include "server/report/chart.h"

namespace enavi::train {
namespace fs = std::filesystem;
namespace rl = navstack::rl;
namespace {

void Check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

void Validate(const TrainOptions& o) {
  Check(!o.boards.empty(), "--boards: at least one board");
  const auto known = [](const std::vector<std::string>& names, const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
  };
  const auto join = [](const std::vector<std::string>& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
  };
  for (const auto& b : o.boards)
    Check(known(o.catalog.boards, b), "--boards: unknown board '" + b + "' (known: " + join(o.catalog.boards) + ")");
  Check(!o.scenarios.empty(), "--scenarios: at least one scenario");
  for (const auto& s : o.scenarios)
    Check(known(o.catalog.scenarios, s),
          "--scenarios: unknown scenario '" + s + "' (known: " + join(o.catalog.scenarios) + ")");
  Check(o.iterations >= 1 && o.iterations <= 100000, "--iterations: must be in [1, 100000]");
  Check(o.episodes_per_iteration >= 1 && o.episodes_per_iteration <= 10000,
        "--episodes-per-iter: must be in [1, 10000]");
  Check(o.workers >= 1 && o.workers <= 64, "--workers: must be in [1, 64]");
  Check(o.eval_every >= 0, "--eval-every: must be >= 0 (0: no evaluation)");
  Check(o.eval_every == 0 || !o.eval_seeds.empty(), "--eval-seeds: at least one seed when evaluating");
  for (const std::uint64_t s : o.eval_seeds)
    Check(s < o.world_seed_base || s >= o.world_seed_base + o.world_seed_count,
          "--eval-seeds: seed " + std::to_string(s) + " is a training seed (training draws [" +
              std::to_string(o.world_seed_base) + ", " + std::to_string(o.world_seed_base + o.world_seed_count) + "))");
  o.ppo.Validate();
}

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct Pick {
  std::string board, scenario;
  std::uint64_t seed = 0;
};

// A collection job: these episodes, the policy by hash, sampled (training) or greedy (evaluation)
// actions.
std::string CollectionJobYaml(const std::string& name, const std::string& policy_ref, const std::vector<Pick>& picks,
                              bool sample) {
  std::ostringstream y;
  y << "name: " << name << "\n"
    << "methods: [enavi]\n"
    << "collect: rollouts\n"
    << "sample: " << (sample ? "true" : "false") << "\n"
    << "policy: \"" << policy_ref << "\"\n"
    << "episodes:\n";
  for (const Pick& p : picks) {
    y << "  - {board: \"" << p.board << "\", scenario: \"" << p.scenario << "\", seed: " << p.seed << "}\n";
  }
  return y.str();
}

// Runs one collection job to its end on the farm; returns its rollouts and result records.
struct Collected {
  std::vector<api::StoredRollout> rollouts;
  nlohmann::json results;
  int failed = 0;
};

Collected Collect(api::FarmClient& client, server::LocalFarm* local, const std::string& yaml,
                  const std::string& what) {
  const auto submitted = client.Submit(yaml, what);
  while (true) {
    const api::JobProgress p = client.Status(submitted.job_id);
    if (p.terminal()) {
      Collected c;
      c.failed = p.failed;
      c.rollouts = client.Rollouts(submitted.job_id);
      c.results = client.Results(submitted.job_id);
      return c;
    }
    if (local) local->CheckWorkers();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

// The evaluation worlds: every scenario once per evaluation seed, boards in turn; the same set at
// every evaluation of a run.
std::vector<Pick> EvaluationPicks(const TrainOptions& o) {
  std::vector<Pick> picks;
  for (std::size_t s = 0; s < o.scenarios.size(); ++s)
    for (std::size_t k = 0; k < o.eval_seeds.size(); ++k) {
      const std::size_t i = s * o.eval_seeds.size() + k;
      picks.push_back({o.boards[i % o.boards.size()], o.scenarios[s], o.eval_seeds[k]});
    }
  return picks;
}

// Sums of the collected rollouts of exactly `hash` into `row`'s means; the others are refused and
// counted as failed. Returns the accepted rollouts.
template <typename Row>
std::vector<rl::Rollout> AcceptRollouts(const Collected& data, const std::string& hash, std::int64_t policy_iteration,
                                        Row* row) {
  std::vector<rl::Rollout> rollouts;
  for (const api::StoredRollout& s : data.rollouts) {
    if (s.policy_hash != hash) {
      std::fprintf(stderr, "\ntrain: rollout of %s refused: policy %s is not this iteration's\n",
                   s.episode_id.c_str(), s.policy_hash.c_str());
      ++row->failed_episodes;
      continue;
    }
    rl::Rollout r = rl::DecodeRollout(s.rollout, "rollout of " + s.episode_id);
    r.id = s.episode_id;
    r.policy_iteration = policy_iteration;
    r.info = {{"success", s.success ? 1.0 : 0.0}, {"collided", s.collided ? 1.0 : 0.0},
              {"flight_time_s", s.flight_time_s}, {"nav_cpu_util_pct", s.nav_cpu_util_pct}};
    row->success_rate += s.success ? 1.0 : 0.0;
    row->collision_rate += s.collided ? 1.0 : 0.0;
    row->mean_nav_cpu += s.nav_cpu_util_pct;
    row->mean_flight_time += s.flight_time_s;
    rollouts.push_back(std::move(r));
  }
  const double n = static_cast<double>(rollouts.size());
  row->episodes = static_cast<int>(rollouts.size());
  if (n > 0) {
    row->success_rate /= n;
    row->collision_rate /= n;
    row->mean_nav_cpu /= n;
    row->mean_flight_time /= n;
  }
  return rollouts;
}

// One curve's plotted columns; `x` is the row's iteration field.
struct CurveColumns {
  std::vector<double> x, ret, success, cpu, time;
};
template <typename Row>
CurveColumns Columns(const std::vector<Row>& rows, std::int64_t Row::*x) {
  CurveColumns c;
  for (const Row& r : rows) {
    c.x.push_back(static_cast<double>(r.*x));
    c.ret.push_back(r.mean_return);
    c.success.push_back(100.0 * r.success_rate);
    c.cpu.push_back(r.mean_nav_cpu);
    c.time.push_back(r.mean_flight_time);
  }
  return c;
}

void SaveCurvePng(const std::vector<IterationLog>& log, const std::vector<EvaluationLog>& evals,
                  const fs::path& path) {
  const CurveColumns t = Columns(log, &IterationLog::iteration);
  const CurveColumns e = Columns(evals, &EvaluationLog::policy_iteration);
  report::ChartStack stack("E-Navi frequency adapter: PPO learning curve", "iteration (policy updates)");
  stack.AddPanel("mean episode return", "return")
      .AddSeries("training (sampled, new worlds each iteration)", t.x, t.ret)
      .AddSeries("evaluation (greedy, fixed worlds)", e.x, e.ret);
  stack.AddPanel("success rate", "%").AddSeries("training", t.x, t.success).AddSeries("evaluation", e.x, e.success);
  stack.AddPanel("navigation CPU (% of one core)", "%").AddSeries("training", t.x, t.cpu).AddSeries("evaluation", e.x, e.cpu);
  stack.AddPanel("flight time", "s").AddSeries("training", t.x, t.time).AddSeries("evaluation", e.x, e.time);
  stack.SavePng(path.string());
}

}  // namespace

std::string LearningCurveCsv(const std::vector<IterationLog>& log) {
  std::string out =
      "iteration,episodes,failed_episodes,mean_return,success_rate,collision_rate,mean_nav_cpu,mean_flight_time,"
      "policy_loss,value_loss,entropy,approx_kl,episodes_per_s\n";
  char line[512];
  for (const auto& r : log) {
    std::snprintf(line, sizeof line, "%lld,%d,%d,%.6f,%.4f,%.4f,%.3f,%.3f,%.6f,%.6f,%.6f,%.6f,%.4f\n",
                  static_cast<long long>(r.iteration), r.episodes, r.failed_episodes, r.mean_return, r.success_rate,
                  r.collision_rate, r.mean_nav_cpu, r.mean_flight_time, r.policy_loss, r.value_loss, r.entropy,
                  r.approx_kl, r.episodes_per_s);
    out += line;
  }
  return out;
}

std::string EvaluationCurveCsv(const std::vector<EvaluationLog>& log) {
  std::string out =
      "policy_iteration,episodes,failed_episodes,mean_return,success_rate,collision_rate,mean_nav_cpu,"
      "mean_flight_time\n";
  char line[256];
  for (const auto& e : log) {
    std::snprintf(line, sizeof line, "%lld,%d,%d,%.6f,%.4f,%.4f,%.3f,%.3f\n",
                  static_cast<long long>(e.policy_iteration), e.episodes, e.failed_episodes, e.mean_return,
                  e.success_rate, e.collision_rate, e.mean_nav_cpu, e.mean_flight_time);
    out += line;
  }
  return out;
}

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(IterationLog, iteration, episodes, failed_episodes, mean_return, success_rate,
                                   collision_rate, mean_nav_cpu, mean_flight_time, policy_loss, value_loss, entropy,
                                   approx_kl, episodes_per_s)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(EvaluationLog, policy_iteration, episodes, failed_episodes, mean_return,
                                   success_rate, collision_rate, mean_nav_cpu, mean_flight_time)

TrainResult Train(const TrainOptions& options) {
  Validate(options);
  const fs::path work = options.work_dir.empty() ? fs::path(options.out.string() + ".train") : options.work_dir;
  fs::create_directories(work);
  const fs::path checkpoint = work / "checkpoint.json";
  const fs::path curve_json = work / "learning_curve.json";
  const fs::path evaluation_json = work / "evaluation_curve.json";

  // The trainer: resumed from its checkpoint, or a fresh (or given) policy.
  TrainResult result;
  std::vector<IterationLog>& log = result.iterations;
  std::vector<EvaluationLog>& evals = result.evaluations;
  auto trainer = [&]() -> rl::PpoTrainer {
    if (options.resume) {
      if (!fs::exists(checkpoint)) throw std::invalid_argument("--resume: no checkpoint at " + checkpoint.string());
      return rl::PpoTrainer::LoadCheckpoint(checkpoint.string());
    }
    rl::PolicyFile init = options.init_policy.empty() ? rl::MakeFrequencyPolicy(navstack::ActionGrid(), options.seed, options.head)
                                                      : rl::LoadFrequencyPolicy(options.init_policy);
    return rl::PpoTrainer(std::move(init), options.ppo, options.seed);
  }();
  if (options.resume) {
    // The curves up to the checkpoint (a run killed after writing them but before the checkpoint
    // repeats that iteration).
    if (fs::exists(curve_json))
      for (const IterationLog& l : nlohmann::json::parse(ReadFile(curve_json)).get<std::vector<IterationLog>>())
        if (l.iteration < trainer.iteration()) log.push_back(l);
    if (fs::exists(evaluation_json))
      for (const EvaluationLog& e : nlohmann::json::parse(ReadFile(evaluation_json)).get<std::vector<EvaluationLog>>())
        if (e.policy_iteration <= trainer.iteration()) evals.push_back(e);
  }
  const auto save_curves = [&] {
    api::WriteFileAtomic(curve_json, nlohmann::json(log).dump(1));
    api::WriteFileAtomic(evaluation_json, nlohmann::json(evals).dump(1));
    api::WriteFileAtomic(work / "learning_curve.csv", LearningCurveCsv(log));
    api::WriteFileAtomic(work / "evaluation_curve.csv", EvaluationCurveCsv(evals));
    SaveCurvePng(log, evals, work / "learning_curve.png");
  };

  // The farm: a running one, or a private one for this run.
  std::unique_ptr<server::LocalFarm> local;
  std::string url = options.server;
  if (url.empty()) {
    server::LocalFarmOptions farm;
    farm.workers = options.workers;
    farm.name = "train";
    farm.http = true;
    farm.job_spec.catalog = options.catalog;
    local = std::make_unique<server::LocalFarm>(farm);
    url = local->url();
  }
  api::FarmClient client(url, options.token);

  // The policy goes to the farm by content hash; only rollouts of exactly it are used.
  const auto upload = [&](std::string* hash) {
    const std::string policy_text = rl::CanonicalPolicyText(trainer.policy());
    *hash = api::Sha256Hex(policy_text);
    const std::string policy_ref = client.UploadPolicy(policy_text);
    if (policy_ref != api::kPolicyHashPrefix + *hash) {
      throw std::runtime_error("train: the farm stored the policy as " + policy_ref + ", expected sha256:" + *hash);
    }
    return policy_ref;
  };
  // The greedy policy as it is now on the evaluation worlds, unless that point is already there.
  const std::vector<Pick> eval_picks = EvaluationPicks(options);
  const auto evaluate = [&](const std::string& policy_ref, const std::string& hash) {
    const std::int64_t at = trainer.iteration();
    if (options.eval_every == 0 || (!evals.empty() && evals.back().policy_iteration >= at)) return;
    const Collected data = Collect(client, local.get(),
                                   CollectionJobYaml("train-eval-" + std::to_string(at), policy_ref, eval_picks, false),
                                   "train evaluation after " + std::to_string(at) + " updates");
    // What was flown, and the policy that flew it (its float64 canonical text, the bytes the farm
    // flew: a float32 copy flies a slightly different flight), for looking back at a point.
    api::WriteFileAtomic(work / ("policy_after_" + std::to_string(at) + ".json"), rl::CanonicalPolicyText(trainer.policy()));
    {
      std::ofstream flights(work / "evaluations.jsonl", std::ios::app);
      for (nlohmann::json line : data.results) {
        line["policy_iteration"] = at;
        flights << line.dump() << "\n";
      }
    }
    EvaluationLog e;
    e.policy_iteration = at;
    e.failed_episodes = data.failed;
    double total = 0;
    for (const rl::Rollout& r : AcceptRollouts(data, hash, at, &e)) total += r.Return();
    if (e.episodes == 0) throw std::runtime_error("train: every evaluation flight after " + std::to_string(at) + " updates failed");
    e.mean_return = total / e.episodes;
    evals.push_back(e);
    save_curves();
    if (options.progress)
      std::fprintf(stderr, "eval after %lld updates  %d flights  return %.2f  success %.0f%%  nav cpu %.1f%%  flight %.1f s\n",
                   static_cast<long long>(at), e.episodes, e.mean_return, 100 * e.success_rate, e.mean_nav_cpu,
                   e.mean_flight_time);
  };

  const auto t_start = std::chrono::steady_clock::now();
  const std::int64_t first = trainer.iteration();
  for (std::int64_t it = first; it < options.iterations; ++it) {
    std::string hash;
    const std::string policy_ref = upload(&hash);  // evaluated and trained on: the same policy
    if (options.eval_every > 0 && it % options.eval_every == 0) evaluate(policy_ref, hash);
    const auto t0 = std::chrono::steady_clock::now();

    // This iteration's episodes: every scenario in turn (so each iteration sees the same mix and
    // its statistics compare across iterations), boards in turn, training-only world seeds.
    std::vector<Pick> picks;
    const int E = options.episodes_per_iteration;
    for (int e = 0; e < E; ++e) {
      const std::uint64_t k = static_cast<std::uint64_t>(it) * E + e;
      picks.push_back({options.boards[(k / options.scenarios.size()) % options.boards.size()],
                       options.scenarios[k % options.scenarios.size()],
                       options.world_seed_base + (options.seed * 7919 + k) % options.world_seed_count});
    }
    const Collected data = Collect(client, local.get(),
                                   CollectionJobYaml("train-iter-" + std::to_string(it), policy_ref, picks, true),
                                   "train iteration " + std::to_string(it));

    IterationLog row;
    row.iteration = it;
    row.failed_episodes = data.failed;
    // Every training flight's result, for looking back at what the policy did (episodes.jsonl).
    {
      std::ofstream episodes(work / "episodes.jsonl", std::ios::app);
      for (nlohmann::json line : data.results) {
        line["iteration"] = it;
        episodes << line.dump() << "\n";
      }
    }
    const std::vector<rl::Rollout> rollouts = AcceptRollouts(data, hash, trainer.iteration(), &row);
    if (rollouts.empty()) throw std::runtime_error("train: every episode of iteration " + std::to_string(it) + " failed");
    const rl::PpoUpdateStats stats = trainer.Update(rollouts);
    row.mean_return = stats.mean_rollout_return;
    row.policy_loss = stats.loss.policy;
    row.value_loss = stats.loss.value;
    row.entropy = stats.loss.entropy;
    row.approx_kl = stats.loss.approx_kl;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    row.episodes_per_s = wall > 0 ? E / wall : 0;
    log.push_back(row);

    // Checkpoint after every iteration: a killed run resumes here.
    trainer.SaveCheckpoint(checkpoint.string());
    save_curves();

    if (options.progress) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      const double per_iter = elapsed / static_cast<double>(it - first + 1);
      std::fprintf(stderr,
                   "iter %lld/%d  %d episodes  %.2f ep/s  return %.2f  success %.0f%%  nav cpu %.1f%%  ETA %.0f s\n",
                   static_cast<long long>(it + 1), options.iterations, row.episodes, row.episodes_per_s, row.mean_return,
                   100 * row.success_rate, row.mean_nav_cpu, per_iter * (options.iterations - it - 1));
    }
  }
  if (options.eval_every > 0) {  // the final policy
    std::string hash;
    const std::string policy_ref = upload(&hash);
    evaluate(policy_ref, hash);
  }
  rl::SavePolicyFile(options.out.string(), trainer.policy());
  return result;
}

}  // namespace enavi::train
