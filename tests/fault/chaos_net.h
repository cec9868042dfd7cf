#pragma once
// Network namespaces for the chaos harness: a hub namespace holding a bridge, and one namespace
// per node (the server, each worker) joined to it by a veth pair, so the farm's traffic crosses
// links this test owns and can degrade. Loss and jitter come from `tc netem` on both ends of a
// node's veth; on a kernel without sch_netem, loss alone comes from an nftables rule (numgen
// random) and `mode()` says jitter is unavailable. A partition drops everything on a node's link
// (nftables) until healed. Every namespace carries the prefix "enavi-fault-<pid>-"; the
// destructor deletes them all, also after a failure, and a new run first removes those a killed
// run left (their pid is gone).

#include <sys/types.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace enavi::testing {

class ChaosNet {
 public:
  /// Creates the hub and one namespace per node (addresses 10.77.0.1, .2, ... in order).
  /// @throws std::runtime_error naming the failed command.
  ChaosNet(const std::vector<std::string>& nodes, std::filesystem::path log_dir);
  ~ChaosNet();
  ChaosNet(const ChaosNet&) = delete;
  ChaosNet& operator=(const ChaosNet&) = delete;

  std::string Namespace(const std::string& node) const { return prefix_ + node; }
  std::string Address(const std::string& node) const { return addresses_.at(node); }
  const std::string& prefix() const { return prefix_; }

  /// `loss_percent` loss and `jitter_ms` jitter (around a delay of the same size) each way on
  /// the node's link.
  void Degrade(const std::string& node, int loss_percent, int jitter_ms);
  /// Drops every packet to and from the node / lets them through again.
  void Partition(const std::string& node);
  void Heal(const std::string& node);
  /// How links are degraded: "netem", or "nftables (...: loss only, no jitter)"; "none" before.
  const std::string& mode() const { return mode_; }

  /// Deletes every namespace with `prefix`; returns how many there were.
  static int RemoveNamespaces(const std::string& prefix);
  /// Names of the namespaces with `prefix` (ip netns list).
  static std::vector<std::string> ListNamespaces(const std::string& prefix);

 private:
  static void RemoveOrphans();
  void Run(const std::vector<std::string>& argv);
  bool TryRun(const std::vector<std::string>& argv);

  std::filesystem::path log_dir_;
  std::string prefix_;
  std::map<std::string, std::string> addresses_, hub_ends_;
  std::string mode_ = "none";
};

}  // namespace enavi::testing
