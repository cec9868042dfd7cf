#include "navstack/rl/policy.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace enavi::navstack::rl {
namespace {

std::vector<int> LayerSizes(int in, const std::vector<int>& hidden, int out) {
  std::vector<int> sizes{in};
  sizes.insert(sizes.end(), hidden.begin(), hidden.end());
  sizes.push_back(out);
  return sizes;
}

void CheckMask(std::span<const std::uint8_t> mask, int num_actions) {
  if (static_cast<int>(mask.size()) != num_actions) {
    throw std::invalid_argument("action mask has " + std::to_string(mask.size()) +
                                " entries, the policy has " + std::to_string(num_actions) +
                                " actions");
  }
}

void CheckHead(const ActorCriticConfig& c) {
  if (!c.factored()) return;
  if (c.head_outputs < 1) throw std::invalid_argument("factored head: head_outputs must be >= 1");
  if (static_cast<int>(c.action_terms.size()) != c.num_actions) {
    throw std::invalid_argument("factored head: " + std::to_string(c.action_terms.size()) +
                                " term lists for " + std::to_string(c.num_actions) + " actions");
  }
  for (const std::vector<int>& terms : c.action_terms) {
    if (terms.empty()) throw std::invalid_argument("factored head: an action has no terms");
    for (int k : terms) {
      if (k < 0 || k >= c.head_outputs) {
        throw std::invalid_argument("factored head: term " + std::to_string(k) + " outside [0, " +
                                    std::to_string(c.head_outputs) + ")");
      }
    }
  }
}

const ActorCriticConfig& Checked(const ActorCriticConfig& c) {
  CheckHead(c);
  return c;
}

}  // namespace

void ObservationNormaliser::Update(const Eigen::Ref<const Eigen::MatrixXd>& X) {
  const double n = static_cast<double>(X.cols());
  if (n == 0) return;
  const Eigen::VectorXd batch_mean = X.rowwise().mean();
  const Eigen::VectorXd batch_var =
      (X.colwise() - batch_mean).array().square().rowwise().sum().matrix() / n;
  // Chan et al. parallel merge of (count, mean, M2).
  const double total = count + n;
  const Eigen::VectorXd delta = batch_mean - mean;
  const Eigen::VectorXd m2 = var * count + batch_var * n + delta.cwiseProduct(delta) * count * n / total;
  mean += delta * (n / total);
  var = m2 / total;
  count = total;
}

void ObservationNormaliser::Normalise(const Eigen::Ref<const Eigen::VectorXd>& x,
                                      Eigen::Ref<Eigen::VectorXd> out) const {
  out = ((x - mean).array() / (var.array() + epsilon).sqrt()).cwiseMax(-clip).cwiseMin(clip).matrix();
}

Eigen::MatrixXd ObservationNormaliser::NormaliseBatch(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  const Eigen::ArrayXd inv_std = (var.array() + epsilon).sqrt().inverse();
  Eigen::MatrixXd out = X.colwise() - mean;
  out = (out.array().colwise() * inv_std).cwiseMax(-clip).cwiseMin(clip).matrix();
  return out;
}

void MaskedLogSoftmax(const Eigen::Ref<const Eigen::VectorXd>& logits,
                      std::span<const std::uint8_t> mask, Eigen::Ref<Eigen::VectorXd> log_probs) {
  const Eigen::Index n = logits.size();
  CheckMask(mask, static_cast<int>(n));
  double max_logit = -std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < n; ++i) {
    if (mask[static_cast<std::size_t>(i)] && logits[i] > max_logit) max_logit = logits[i];
  }
  if (max_logit == -std::numeric_limits<double>::infinity()) {
    throw std::invalid_argument("action mask has no feasible action");
  }
  double sum = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (mask[static_cast<std::size_t>(i)]) sum += std::exp(logits[i] - max_logit);
  }
  const double lse = max_logit + std::log(sum);
  for (Eigen::Index i = 0; i < n; ++i) {
    log_probs[i] = mask[static_cast<std::size_t>(i)] ? logits[i] - lse
                                                     : -std::numeric_limits<double>::infinity();
  }
}

ActorCritic::ActorCritic(const ActorCriticConfig& config)
    : config_(Checked(config)),
      actor_(LayerSizes(config.obs_dim, config.hidden, config.actor_outputs())),
      critic_(LayerSizes(config.obs_dim, config.hidden, 1)),
      normaliser_(config.obs_dim) {}

void ActorCritic::Logits(const Eigen::Ref<const Eigen::MatrixXd>& head, Eigen::Ref<Eigen::MatrixXd> logits) const {
  if (!config_.factored()) {
    logits = head;
    return;
  }
  logits.setZero();
  for (int a = 0; a < num_actions(); ++a) {
    for (int k : config_.action_terms[static_cast<std::size_t>(a)]) logits.row(a) += head.row(k);
  }
}

void ActorCritic::HeadGradient(const Eigen::Ref<const Eigen::MatrixXd>& d_logits,
                               Eigen::MatrixXd* d_head) const {
  if (!config_.factored()) {
    *d_head = d_logits;
    return;
  }
  d_head->setZero(config_.head_outputs, d_logits.cols());
  for (int a = 0; a < num_actions(); ++a) {
    for (int k : config_.action_terms[static_cast<std::size_t>(a)]) d_head->row(k) += d_logits.row(a);
  }
}

void ActorCritic::InitializeWeights(Rng* rng) {
  actor_.InitOrthogonal(rng, 0.01);
  critic_.InitOrthogonal(rng, 1.0);
}

ActorCritic::Workspace ActorCritic::MakeWorkspace() const {
  Workspace ws;
  ws.obs.resize(obs_dim());
  ws.head.resize(config_.actor_outputs());
  ws.logits.resize(num_actions());
  ws.log_probs.resize(num_actions());
  ws.value.resize(1);
  ws.actor = actor_.MakeWorkspace();
  ws.critic = critic_.MakeWorkspace();
  return ws;
}

PolicyOutput ActorCritic::Act(const Eigen::Ref<const Eigen::VectorXd>& obs,
                              std::span<const std::uint8_t> mask, ActMode mode, Rng* rng,
                              Workspace* ws, bool want_log_prob, bool want_value) const {
  if (obs.size() != obs_dim()) {
    throw std::invalid_argument("observation has " + std::to_string(obs.size()) +
                                " features, the policy expects " + std::to_string(obs_dim()));
  }
  CheckMask(mask, num_actions());
  normaliser_.Normalise(obs, ws->obs);
  if (config_.factored()) {
    actor_.Forward(ws->obs, &ws->actor, ws->head);
    Logits(ws->head, ws->logits);
  } else {
    actor_.Forward(ws->obs, &ws->actor, ws->logits);
  }

  PolicyOutput out;
  if (mode == ActMode::kGreedy) {
    // Argmax over feasible actions; ties go to the lowest index (the cheapest, by grid order).
    double best = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < num_actions(); ++i) {
      if (mask[static_cast<std::size_t>(i)] && (out.action < 0 || ws->logits[i] > best)) {
        best = ws->logits[i];
        out.action = i;
      }
    }
    if (out.action < 0) throw std::invalid_argument("action mask has no feasible action");
    if (want_log_prob) {
      MaskedLogSoftmax(ws->logits, mask, ws->log_probs);
      out.log_prob = ws->log_probs[out.action];
    }
  } else {
    if (rng == nullptr) throw std::logic_error("ActorCritic::Act: sample mode needs an rng");
    MaskedLogSoftmax(ws->logits, mask, ws->log_probs);
    // Inverse CDF over feasible actions only; rounding leftovers land on the last feasible one.
    const double u = rng->Uniform01();
    double cdf = 0.0;
    for (int i = 0; i < num_actions(); ++i) {
      if (!mask[static_cast<std::size_t>(i)]) continue;
      out.action = i;
      cdf += std::exp(ws->log_probs[i]);
      if (u < cdf) break;
    }
    out.log_prob = ws->log_probs[out.action];
  }
  if (want_value) {
    critic_.Forward(ws->obs, &ws->critic, ws->value);
    out.value = ws->value[0];
  }
  return out;
}

std::int64_t ActorCritic::MacsPerDecision(bool with_value) const {
  std::int64_t head_sums = 0;
  for (const std::vector<int>& terms : config_.action_terms) head_sums += static_cast<std::int64_t>(terms.size());
  return actor_.MacsPerSample() + head_sums + (with_value ? critic_.MacsPerSample() : 0);
}

}  // namespace enavi::navstack::rl
