#include "tests/fault/chaos_net.h"

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "workers/worker/process.h"

namespace enavi::testing {
namespace {

namespace fs = std::filesystem;

std::string Join(const std::vector<std::string>& argv) {
  std::string out;
  for (const auto& a : argv) {
    if (!out.empty()) out += ' ';
    out += a;
  }
  return out;
}

std::string ReadAll(const fs::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs a command to completion (30 s at most); returns its exit status and output.
bool RunCommand(const std::vector<std::string>& argv, const fs::path& out, std::string* output) {
  worker::SpawnOptions o;
  o.argv = argv;
  o.stdout_file = out;
  o.stderr_file = out;
  const auto status = worker::ChildProcess::Spawn(o).Wait(std::chrono::seconds(30));
  if (output != nullptr) *output = ReadAll(out);
  return status && status->ok();
}

// nftables rules of one node's link: `verdict` for a share of the packets each way.
std::string NftTable(const std::string& table, const std::string& match) {
  return "table inet " + table + " {\n"
         "  chain in { type filter hook input priority -10; iifname \"eth0\" " + match + "; }\n"
         "  chain out { type filter hook output priority -10; oifname \"eth0\" " + match + "; }\n"
         "}\n";
}

constexpr const char* kNftMode = "nftables (no sch_netem in this kernel: loss only, no jitter)";

}  // namespace

ChaosNet::ChaosNet(const std::vector<std::string>& nodes, fs::path log_dir)
    : log_dir_(std::move(log_dir)), prefix_("enavi-fault-" + std::to_string(getpid()) + "-") {
  RemoveOrphans();
  const std::string hub = Namespace("hub");
  Run({"ip", "netns", "add", hub});
  Run({"ip", "-n", hub, "link", "add", "br0", "type", "bridge"});
  Run({"ip", "-n", hub, "link", "set", "br0", "up"});
  int host = 1;
  for (const auto& node : nodes) {
    // (Appended, not "h" + to_string: GCC 12 warns falsely about the latter, -Wrestrict.)
    const std::string ns = Namespace(node), number = std::to_string(host++);
    std::string hub_end = "h";
    hub_end += number;
    addresses_[node] = std::string("10.77.0.").append(number);
    hub_ends_[node] = hub_end;
    Run({"ip", "netns", "add", ns});
    // Both ends made in the hub and the node's end moved: nothing touches the host's namespace.
    Run({"ip", "-n", hub, "link", "add", hub_end, "type", "veth", "peer", "name", "eth0", "netns", ns});
    Run({"ip", "-n", hub, "link", "set", hub_end, "master", "br0", "up"});
    Run({"ip", "-n", ns, "addr", "add", addresses_[node] + "/24", "dev", "eth0"});
    Run({"ip", "-n", ns, "link", "set", "eth0", "up"});
    Run({"ip", "-n", ns, "link", "set", "lo", "up"});
  }
}

ChaosNet::~ChaosNet() { RemoveNamespaces(prefix_); }

void ChaosNet::Degrade(const std::string& node, int loss_percent, int jitter_ms) {
  const std::string ns = Namespace(node);
  const std::vector<std::string> netem = {"netem", "delay", std::to_string(jitter_ms) + "ms",
                                          std::to_string(jitter_ms) + "ms", "loss",
                                          std::to_string(loss_percent) + "%"};
  auto qdisc = [&](const std::string& in_ns, const std::string& dev) {
    std::vector<std::string> argv = {"tc", "-n", in_ns, "qdisc", "add", "dev", dev, "root"};
    argv.insert(argv.end(), netem.begin(), netem.end());
    return argv;
  };
  if (mode_ != kNftMode && TryRun(qdisc(ns, "eth0"))) {
    Run(qdisc(Namespace("hub"), hub_ends_.at(node)));
    mode_ = "netem";
    return;
  }
  // No sch_netem in this kernel: loss from nftables, no jitter.
  const fs::path rules = log_dir_ / ("loss-" + node + ".nft");
  std::ofstream(rules) << NftTable("enavi_loss", "numgen random mod 100 < " +
                                                     std::to_string(loss_percent) + " drop");
  Run({"ip", "netns", "exec", ns, "nft", "-f", rules.string()});
  mode_ = kNftMode;
}

void ChaosNet::Partition(const std::string& node) {
  const fs::path rules = log_dir_ / ("partition-" + node + ".nft");
  std::ofstream(rules) << NftTable("enavi_partition", "drop");
  Run({"ip", "netns", "exec", Namespace(node), "nft", "-f", rules.string()});
}

void ChaosNet::Heal(const std::string& node) {
  Run({"ip", "netns", "exec", Namespace(node), "nft", "delete", "table", "inet", "enavi_partition"});
}

std::vector<std::string> ChaosNet::ListNamespaces(const std::string& prefix) {
  std::string output;
  const fs::path out = fs::temp_directory_path() / (prefix + "list.txt");
  RunCommand({"ip", "netns", "list"}, out, &output);
  fs::remove(out);
  std::vector<std::string> names;
  std::istringstream lines(output);
  for (std::string line; std::getline(lines, line);) {
    const std::string name = line.substr(0, line.find(' '));
    if (name.rfind(prefix, 0) == 0) names.push_back(name);
  }
  return names;
}

void ChaosNet::RemoveOrphans() {
  // A run killed before its destructor left its namespaces: remove those of dead processes.
  const std::string family = "enavi-fault-";
  for (const auto& name : ListNamespaces(family)) {
    const std::string pid = name.substr(family.size(), name.find('-', family.size()) - family.size());
    if (pid == std::to_string(getpid()) || !fs::exists("/proc/" + pid)) {
      RemoveNamespaces(family + pid + "-");
    }
  }
}

int ChaosNet::RemoveNamespaces(const std::string& prefix) {
  const auto names = ListNamespaces(prefix);
  const fs::path out = fs::temp_directory_path() / (prefix + "del.txt");
  for (const auto& name : names) RunCommand({"ip", "netns", "del", name}, out, nullptr);
  fs::remove(out);
  return static_cast<int>(names.size());
}

void ChaosNet::Run(const std::vector<std::string>& argv) {
  std::string output;
  if (!RunCommand(argv, log_dir_ / "net-command.log", &output)) {
    throw std::runtime_error(Join(argv) + ": " + output);
  }
}

bool ChaosNet::TryRun(const std::vector<std::string>& argv) {
  return RunCommand(argv, log_dir_ / "net-command.log", nullptr);
}

}  // namespace enavi::testing
