#include "navstack/rl/ppo.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "api/atomic_file.h"
#include "navstack/rl/json_read.h"

namespace enavi::navstack::rl {
namespace {

using detail::JsonReader;
using nlohmann::json;

constexpr const char* kCheckpointFormat = "enavi-ppo-checkpoint";
constexpr int kCheckpointVersion = 1;

void RequireRange(double v, double lo, double hi, bool lo_open, bool hi_open, const char* field) {
  const bool ok = (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  if (!ok) {
    std::ostringstream os;
    os << "ppo option " << field << " = " << v << " must be in " << (lo_open ? "(" : "[") << lo
       << ", " << hi << (hi_open ? ")" : "]");
    throw std::invalid_argument(os.str());
  }
}

double SquaredNorm(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.squaredNorm() + b.squaredNorm();
}

json AdamToJson(const AdamState& s) {
  return {{"t", s.t}, {"m", detail::ToJson(s.m)}, {"v", detail::ToJson(s.v)}};
}

AdamState AdamFromJson(const json& j, const std::string& field, const JsonReader& r,
                       Eigen::Index size) {
  AdamState s;
  s.t = r.Integer(r.Field(j, field, "t"), field + ".t");
  if (s.t < 0) r.Fail(field + ".t", "must be >= 0");
  s.m = r.Vector(r.Field(j, field, "m"), field + ".m", size);
  s.v = r.Vector(r.Field(j, field, "v"), field + ".v", size);
  if ((s.v.array() < 0.0).any()) r.Fail(field + ".v", "second moments must be >= 0");
  return s;
}

}  // namespace

void PpoOptions::Validate() const {
  RequireRange(gamma, 0, 1, false, false, "gamma");
  RequireRange(lambda, 0, 1, false, false, "lambda");
  RequireRange(clip, 0, 1, true, true, "clip");
  RequireRange(value_coef, 0, 100, false, false, "value_coef");
  RequireRange(entropy_coef, 0, 10, false, false, "entropy_coef");
  RequireRange(learning_rate, 0, 1, true, false, "learning_rate");
  RequireRange(adam_beta1, 0, 1, false, true, "adam_beta1");
  RequireRange(adam_beta2, 0, 1, false, true, "adam_beta2");
  RequireRange(adam_epsilon, 0, 1, true, false, "adam_epsilon");
  RequireRange(epochs, 1, 1000, false, false, "epochs");
  RequireRange(minibatch_size, 1, 1e6, false, false, "minibatch_size");
  RequireRange(max_grad_norm, 0, 1e9, false, false, "max_grad_norm");
  RequireRange(target_kl, 0, 1e3, false, false, "target_kl");
}

json PpoOptionsToJson(const PpoOptions& o) {
  return {{"gamma", o.gamma},
          {"lambda", o.lambda},
          {"clip", o.clip},
          {"value_coef", o.value_coef},
          {"entropy_coef", o.entropy_coef},
          {"learning_rate", o.learning_rate},
          {"adam_beta1", o.adam_beta1},
          {"adam_beta2", o.adam_beta2},
          {"adam_epsilon", o.adam_epsilon},
          {"epochs", o.epochs},
          {"minibatch_size", o.minibatch_size},
          {"max_grad_norm", o.max_grad_norm},
          {"normalise_advantages", o.normalise_advantages},
          {"target_kl", o.target_kl},
          {"update_obs_normaliser", o.update_obs_normaliser}};
}

PpoOptions PpoOptionsFromJson(const json& j, const std::string& source) {
  const JsonReader r(source);
  r.Object(j, "options");
  PpoOptions o;
  const auto num = [&](const char* k) {
    return r.Number(r.Field(j, "options", k), std::string("options.") + k);
  };
  const auto integer = [&](const char* k) {
    const std::int64_t v = r.Integer(r.Field(j, "options", k), std::string("options.") + k);
    if (v < 1 || v > 1000000) r.Fail(std::string("options.") + k, "must be in [1, 1e6]");
    return static_cast<int>(v);
  };
  const auto flag = [&](const char* k) {
    return r.Bool(r.Field(j, "options", k), std::string("options.") + k);
  };
  o.gamma = num("gamma");
  o.lambda = num("lambda");
  o.clip = num("clip");
  o.value_coef = num("value_coef");
  o.entropy_coef = num("entropy_coef");
  o.learning_rate = num("learning_rate");
  o.adam_beta1 = num("adam_beta1");
  o.adam_beta2 = num("adam_beta2");
  o.adam_epsilon = num("adam_epsilon");
  o.epochs = integer("epochs");
  o.minibatch_size = integer("minibatch_size");
  o.max_grad_norm = num("max_grad_norm");
  o.normalise_advantages = flag("normalise_advantages");
  o.target_kl = num("target_kl");
  o.update_obs_normaliser = flag("update_obs_normaliser");
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail("options", e.what());
  }
  return o;
}

PpoBatch PpoBatch::Select(std::span<const int> indices) const {
  PpoBatch out;
  const auto n = static_cast<Eigen::Index>(indices.size());
  const auto a = static_cast<std::size_t>(num_actions);
  out.num_actions = num_actions;
  out.obs.resize(obs.rows(), n);
  out.actions.resize(indices.size());
  out.masks.resize(indices.size() * a);
  out.old_log_probs.resize(n);
  out.advantages.resize(n);
  out.returns.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const int i = indices[static_cast<std::size_t>(k)];
    out.obs.col(k) = obs.col(i);
    out.actions[static_cast<std::size_t>(k)] = actions[static_cast<std::size_t>(i)];
    std::copy_n(masks.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(i) * a), a,
                out.masks.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(k) * a));
    out.old_log_probs[k] = old_log_probs[i];
    out.advantages[k] = advantages[i];
    out.returns[k] = returns[i];
  }
  return out;
}

PpoBatch MakePpoBatch(const ActorCritic& net, const std::vector<Rollout>& rollouts,
                      const PpoOptions& options) {
  // Validate every step before touching anything.
  std::size_t n = 0;
  for (std::size_t r = 0; r < rollouts.size(); ++r) {
    const Rollout& ro = rollouts[r];
    const std::string where = "rollout " + std::to_string(r) + (ro.id.empty() ? "" : " (" + ro.id + ")");
    if (!std::isfinite(ro.bootstrap_value)) {
      throw std::invalid_argument(where + ": bootstrap_value is not finite");
    }
    for (std::size_t t = 0; t < ro.steps.size(); ++t) {
      const RolloutStep& s = ro.steps[t];
      const std::string ws = where + " step " + std::to_string(t);
      if (s.obs.size() != net.obs_dim()) {
        throw std::invalid_argument(ws + ": obs has " + std::to_string(s.obs.size()) +
                                    " features, the policy expects " + std::to_string(net.obs_dim()));
      }
      if (static_cast<int>(s.mask.size()) != net.num_actions()) {
        throw std::invalid_argument(ws + ": mask has " + std::to_string(s.mask.size()) +
                                    " entries, the policy has " + std::to_string(net.num_actions()) +
                                    " actions");
      }
      if (s.action < 0 || s.action >= net.num_actions() || !s.mask[static_cast<std::size_t>(s.action)]) {
        throw std::invalid_argument(ws + ": action " + std::to_string(s.action) + " is not in its mask");
      }
      if (!s.obs.allFinite() || !std::isfinite(s.log_prob) || !std::isfinite(s.value) ||
          !std::isfinite(s.reward)) {
        throw std::invalid_argument(ws + ": non-finite obs, log_prob, value or reward");
      }
    }
    n += ro.steps.size();
  }
  if (n == 0) throw std::invalid_argument("rollouts: no steps to train on");

  PpoBatch b;
  const auto a = static_cast<std::size_t>(net.num_actions());
  b.num_actions = net.num_actions();
  Eigen::MatrixXd raw(net.obs_dim(), static_cast<Eigen::Index>(n));
  b.actions.resize(n);
  b.masks.resize(n * a);
  b.old_log_probs.resize(static_cast<Eigen::Index>(n));
  b.advantages.resize(static_cast<Eigen::Index>(n));
  b.returns.resize(static_cast<Eigen::Index>(n));
  Eigen::Index k = 0;
  for (const Rollout& ro : rollouts) {
    const auto len = static_cast<Eigen::Index>(ro.steps.size());
    ComputeGae(ro, options.gamma, options.lambda, b.advantages.segment(k, len),
               b.returns.segment(k, len));
    for (const RolloutStep& s : ro.steps) {
      raw.col(k) = s.obs;
      b.actions[static_cast<std::size_t>(k)] = s.action;
      std::copy(s.mask.begin(), s.mask.end(),
                b.masks.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(k) * a));
      b.old_log_probs[k] = s.log_prob;
      ++k;
    }
  }
  b.obs = net.normaliser().NormaliseBatch(raw);
  if (options.normalise_advantages && n > 1) {
    const double mean = b.advantages.mean();
    const double std = std::sqrt((b.advantages.array() - mean).square().mean());
    b.advantages = ((b.advantages.array() - mean) / (std + 1e-8)).matrix();
  }
  return b;
}

PpoLossTerms ComputePpoLoss(const ActorCritic& net, const PpoBatch& batch, const PpoOptions& options,
                            PpoGradients* grads) {
  const int n = batch.size();
  if (n == 0) throw std::logic_error("ComputePpoLoss: empty batch");
  const int num_actions = net.num_actions();
  Mlp::BatchCache actor_cache, critic_cache;
  Eigen::MatrixXd head, logits, values;
  net.actor().ForwardBatch(batch.obs, &actor_cache, &head);
  logits.resize(num_actions, n);
  net.Logits(head, logits);
  net.critic().ForwardBatch(batch.obs, &critic_cache, &values);

  const double inv_n = 1.0 / n;
  const double eps = options.clip;
  Eigen::MatrixXd d_logits;
  Eigen::MatrixXd d_values;
  if (grads != nullptr) {
    d_logits = Eigen::MatrixXd::Zero(num_actions, n);
    d_values = Eigen::MatrixXd::Zero(1, n);
  }
  Eigen::VectorXd log_probs(num_actions);
  PpoLossTerms terms;
  for (int i = 0; i < n; ++i) {
    const std::span<const std::uint8_t> mask = batch.mask(i);
    MaskedLogSoftmax(logits.col(i), mask, log_probs);
    const int a = batch.actions[static_cast<std::size_t>(i)];
    const double log_ratio = log_probs[a] - batch.old_log_probs[i];
    const double ratio = std::exp(log_ratio);
    const double adv = batch.advantages[i];
    const double surr1 = ratio * adv;
    const double surr2 = std::clamp(ratio, 1.0 - eps, 1.0 + eps) * adv;
    terms.policy -= std::min(surr1, surr2);
    terms.approx_kl += (ratio - 1.0) - log_ratio;
    if (std::abs(ratio - 1.0) > eps) terms.clip_fraction += 1.0;
    double entropy = 0.0;
    for (int j = 0; j < num_actions; ++j) {
      if (mask[static_cast<std::size_t>(j)]) entropy -= std::exp(log_probs[j]) * log_probs[j];
    }
    terms.entropy += entropy;
    const double v_err = values(0, i) - batch.returns[i];
    terms.value += 0.5 * v_err * v_err;

    if (grads != nullptr) {
      // d(-min(surr1, surr2))/d log pi_a: the unclipped branch carries -A r; the clipped is flat.
      const double g_log_prob = surr1 <= surr2 ? -adv * ratio * inv_n : 0.0;
      // d log pi_a / dz_j = [j = a] - p_j; d(-c_e H)/dz_j = c_e p_j (log p_j + H).
      for (int j = 0; j < num_actions; ++j) {
        if (!mask[static_cast<std::size_t>(j)]) continue;
        const double p = std::exp(log_probs[j]);
        d_logits(j, i) = g_log_prob * ((j == a ? 1.0 : 0.0) - p) +
                         options.entropy_coef * inv_n * p * (log_probs[j] + entropy);
      }
      d_values(0, i) = options.value_coef * v_err * inv_n;
    }
  }
  terms.policy *= inv_n;
  terms.value *= inv_n;
  terms.entropy *= inv_n;
  terms.approx_kl *= inv_n;
  terms.clip_fraction *= inv_n;
  terms.total = terms.policy + options.value_coef * terms.value - options.entropy_coef * terms.entropy;

  if (grads != nullptr) {
    grads->actor = Eigen::VectorXd::Zero(net.actor().num_params());
    grads->critic = Eigen::VectorXd::Zero(net.critic().num_params());
    Eigen::MatrixXd d_head;
    net.HeadGradient(d_logits, &d_head);
    net.actor().BackwardBatch(actor_cache, d_head, grads->actor);
    net.critic().BackwardBatch(critic_cache, d_values, grads->critic);
  }
  return terms;
}

void AdamStep(const PpoOptions& o, const Eigen::Ref<const Eigen::VectorXd>& grad,
              Eigen::Ref<Eigen::VectorXd> params, AdamState* s) {
  if (s->m.size() != params.size()) s->m = Eigen::VectorXd::Zero(params.size());
  if (s->v.size() != params.size()) s->v = Eigen::VectorXd::Zero(params.size());
  ++s->t;
  s->m = o.adam_beta1 * s->m + (1.0 - o.adam_beta1) * grad;
  s->v = o.adam_beta2 * s->v + (1.0 - o.adam_beta2) * grad.cwiseProduct(grad);
  const double c1 = 1.0 - std::pow(o.adam_beta1, static_cast<double>(s->t));
  const double c2 = 1.0 - std::pow(o.adam_beta2, static_cast<double>(s->t));
  params.array() -= o.learning_rate * (s->m.array() / c1) / ((s->v.array() / c2).sqrt() + o.adam_epsilon);
}

PpoTrainer::PpoTrainer(PolicyFile policy, const PpoOptions& options, std::uint64_t seed)
    : policy_(std::move(policy)), options_(options), rng_(seed) {
  options_.Validate();
  adam_actor_.m = Eigen::VectorXd::Zero(policy_.net.actor().num_params());
  adam_actor_.v = adam_actor_.m;
  adam_critic_.m = Eigen::VectorXd::Zero(policy_.net.critic().num_params());
  adam_critic_.v = adam_critic_.m;
}

PpoUpdateStats PpoTrainer::Update(const std::vector<Rollout>& rollouts) {
  if (rollouts.empty()) throw std::invalid_argument("PPO update: no rollouts");
  for (std::size_t r = 0; r < rollouts.size(); ++r) {
    const std::int64_t it = rollouts[r].policy_iteration;
    if (it >= 0 && it != iteration_) {
      throw std::invalid_argument("rollout " + std::to_string(r) + " (" + rollouts[r].id +
                                  "): collected with the policy of iteration " + std::to_string(it) +
                                  ", the trainer is at iteration " + std::to_string(iteration_));
    }
  }
  ActorCritic& net = policy_.net;
  const PpoBatch batch = MakePpoBatch(net, rollouts, options_);
  const int n = batch.size();

  PpoUpdateStats stats;
  stats.iteration = iteration_;
  stats.num_rollouts = static_cast<int>(rollouts.size());
  stats.num_steps = n;
  double total_return = 0.0;
  Eigen::VectorXd old_values(n);
  {
    Eigen::Index k = 0;
    for (const Rollout& ro : rollouts) {
      total_return += ro.Return();
      for (const RolloutStep& s : ro.steps) old_values[k++] = s.value;
    }
  }
  stats.mean_rollout_return = total_return / static_cast<double>(rollouts.size());
  stats.mean_step_reward = total_return / n;
  {
    // Explained variance of the collection-time values against the GAE returns.
    const double var_r = (batch.returns.array() - batch.returns.mean()).square().mean();
    const Eigen::ArrayXd resid = batch.returns.array() - old_values.array();
    const double var_e = (resid - resid.mean()).square().mean();
    stats.explained_variance = var_r > 0.0 ? 1.0 - var_e / var_r : 0.0;
  }

  // Minibatch epochs over a fresh permutation each time (Fisher-Yates on our own RNG).
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  PpoGradients grads;
  double grad_norm_sum = 0.0;
  for (int epoch = 0; epoch < options_.epochs && !stats.stopped_early; ++epoch) {
    for (int i = n - 1; i > 0; --i) {
      const auto j = static_cast<int>(rng_.UniformIndex(static_cast<std::uint64_t>(i) + 1));
      std::swap(order[static_cast<std::size_t>(i)], order[static_cast<std::size_t>(j)]);
    }
    PpoLossTerms epoch_sum;
    int epoch_minibatches = 0;
    for (int start = 0; start < n; start += options_.minibatch_size) {
      const int len = std::min(options_.minibatch_size, n - start);
      const PpoBatch mb = batch.Select(
          std::span<const int>(order.data() + start, static_cast<std::size_t>(len)));
      const PpoLossTerms t = ComputePpoLoss(net, mb, options_, &grads);
      const double norm = std::sqrt(SquaredNorm(grads.actor, grads.critic));
      grad_norm_sum += norm;
      if (options_.max_grad_norm > 0.0 && norm > options_.max_grad_norm) {
        const double scale = options_.max_grad_norm / norm;
        grads.actor *= scale;
        grads.critic *= scale;
      }
      AdamStep(options_, grads.actor, net.actor().params(), &adam_actor_);
      AdamStep(options_, grads.critic, net.critic().params(), &adam_critic_);
      ++stats.minibatch_updates;
      ++epoch_minibatches;
      epoch_sum.total += t.total;
      epoch_sum.policy += t.policy;
      epoch_sum.value += t.value;
      epoch_sum.entropy += t.entropy;
      epoch_sum.approx_kl += t.approx_kl;
      epoch_sum.clip_fraction += t.clip_fraction;
      if (options_.target_kl > 0.0 && t.approx_kl > 1.5 * options_.target_kl) {
        stats.stopped_early = true;
        break;
      }
    }
    const double m = 1.0 / epoch_minibatches;
    stats.loss = {epoch_sum.total * m,     epoch_sum.policy * m,    epoch_sum.value * m,
                  epoch_sum.entropy * m,   epoch_sum.approx_kl * m, epoch_sum.clip_fraction * m};
    ++stats.epochs_done;
  }
  stats.grad_norm = grad_norm_sum / stats.minibatch_updates;

  // The rollouts' raw observations refine the normaliser for the next collection round.
  if (options_.update_obs_normaliser) {
    Eigen::MatrixXd raw(net.obs_dim(), n);
    Eigen::Index k = 0;
    for (const Rollout& ro : rollouts) {
      for (const RolloutStep& s : ro.steps) raw.col(k++) = s.obs;
    }
    net.normaliser().Update(raw);
  }
  ++iteration_;
  return stats;
}

json PpoTrainer::CheckpointToJson() const {
  json j;
  j["format"] = kCheckpointFormat;
  j["version"] = kCheckpointVersion;
  j["iteration"] = iteration_;
  j["rng"] = rng_.SaveState();
  j["options"] = PpoOptionsToJson(options_);
  j["policy"] = PolicyToJson(policy_, WeightPrecision::kFloat64);  // bit-exact resume
  j["adam"] = {{"actor", AdamToJson(adam_actor_)}, {"critic", AdamToJson(adam_critic_)}};
  return j;
}

PpoTrainer PpoTrainer::FromCheckpointJson(const json& j, const std::string& source) {
  const JsonReader r(source);
  r.Object(j, "");
  if (r.String(r.Field(j, "", "format"), "format") != kCheckpointFormat) {
    r.Fail("format", std::string("expected \"") + kCheckpointFormat + "\"");
  }
  const std::int64_t version = r.Integer(r.Field(j, "", "version"), "version");
  if (version != kCheckpointVersion) {
    r.Fail("version", "unsupported version " + std::to_string(version) + " (this build reads " +
                          std::to_string(kCheckpointVersion) + ")");
  }
  const PpoOptions options = PpoOptionsFromJson(r.Field(j, "", "options"), source);
  PolicyFile policy = PolicyFromJson(r.Field(j, "", "policy"), source + ": policy");
  PpoTrainer trainer(std::move(policy), options, 0);
  trainer.iteration_ = r.Integer(r.Field(j, "", "iteration"), "iteration");
  if (trainer.iteration_ < 0) r.Fail("iteration", "must be >= 0");
  try {
    trainer.rng_.LoadState(r.String(r.Field(j, "", "rng"), "rng"));
  } catch (const std::invalid_argument& e) {
    r.Fail("rng", e.what());
  }
  const json& adam = r.Object(r.Field(j, "", "adam"), "adam");
  trainer.adam_actor_ = AdamFromJson(r.Field(adam, "adam", "actor"), "adam.actor", r,
                                     trainer.net().actor().num_params());
  trainer.adam_critic_ = AdamFromJson(r.Field(adam, "adam", "critic"), "adam.critic", r,
                                      trainer.net().critic().num_params());
  return trainer;
}

void PpoTrainer::SaveCheckpoint(const std::string& path) const {
  api::WriteFileAtomic(path, CheckpointToJson().dump() + "\n");
}

PpoTrainer PpoTrainer::LoadCheckpoint(const std::string& path) {
  return FromCheckpointJson(detail::ReadJsonFile(path, "checkpoint"), "checkpoint '" + path + "'");
}

}  // namespace enavi::navstack::rl
