// `enavi policy convert IN --out OUT`: a policy file rewritten in the current format (version 2,
// float32 weights in one base64 block with their sha256) by the trainer's own writer.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <utility>

#include "navstack/rl/policy_io.h"
#include "server/cli/commands.h"

namespace enavi::cli {

void RegisterPolicyCommands(CLI::App& app) {
  CLI::App* policy = app.add_subcommand("policy", "E-Navi policy files");
  policy->require_subcommand(1);
  struct Flags {
    std::string in;
    std::string out;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* convert = policy->add_subcommand(
      "convert", "Rewrite a policy file (any readable version) as version 2 with float32 weights");
  convert->add_option("in", f->in, "policy file to read")->required();
  convert->add_option("--out", f->out, "where the converted policy is written (may be IN)")->required();
  convert->callback([f] {
    const navstack::rl::PolicyFile policy = navstack::rl::LoadPolicyFile(f->in);
    const auto in_bytes = std::filesystem::file_size(f->in);
    navstack::rl::SavePolicyFile(f->out, policy);
    // What float32 storage did to the weights: the largest change, relative to the largest weight.
    const navstack::rl::PolicyFile stored = navstack::rl::LoadPolicyFile(f->out);
    double max_change = 0.0;
    double max_weight = 0.0;
    for (const auto& [a, b] : {std::pair{&policy.net.actor(), &stored.net.actor()},
                               std::pair{&policy.net.critic(), &stored.net.critic()}}) {
      max_change = std::max(max_change, (a->params() - b->params()).cwiseAbs().maxCoeff());
      max_weight = std::max(max_weight, a->params().cwiseAbs().maxCoeff());
    }
    std::printf("%s: version %d, %lld float32 weights, %ju bytes (was %ju); largest change %.3g (%.3g of the "
                "largest weight)\n",
                f->out.c_str(), navstack::rl::kPolicyVersion,
                static_cast<long long>(policy.net.actor().num_params() + policy.net.critic().num_params()),
                static_cast<std::uintmax_t>(std::filesystem::file_size(f->out)),
                static_cast<std::uintmax_t>(in_bytes), max_change, max_weight > 0 ? max_change / max_weight : 0.0);
  });
}

}  // namespace enavi::cli
