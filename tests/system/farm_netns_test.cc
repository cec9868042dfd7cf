// Many hosts: the server and two workers each in their own network namespace, joined by veth
// pairs on a bridge, finding each other through unicast peers only (no multicast), exactly as
// separate machines would. Needs root (ip netns add); skipped otherwise.
#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <exception>

#include "tests/system/farm_harness.h"

namespace enavi::testing {
namespace {

//            hub namespace: bridge br0
//         veth       veth       veth
//          |          |          |
//   server (.1)    w1 (.2)    w2 (.3)      subnet 10.A.B.0/24, unique per test process
class NetnsFarm : public FarmFixture {
 protected:
  void SetUp() override {
    if (geteuid() != 0) {
      GTEST_SKIP() << "needs root to create network namespaces (ip netns add); run as root, "
                      "as CI does";
    }
    if (access("/usr/sbin/ip", X_OK) != 0 && access("/sbin/ip", X_OK) != 0 &&
        access("/usr/bin/ip", X_OK) != 0) {
      GTEST_SKIP() << "needs the ip command (iproute2)";
    }
    FarmFixture::SetUp();
    tag_ = "en" + std::to_string(getpid());
    const int p = static_cast<int>(getpid());
    subnet_ = "10." + std::to_string(100 + p % 100) + "." + std::to_string((p / 100) % 250) + ".";
    Ip({"netns", "add", Ns("hub")});
    Ip({"-n", Ns("hub"), "link", "add", "br0", "type", "bridge"});
    Ip({"-n", Ns("hub"), "link", "set", "br0", "up"});
    int host = 1;
    for (const std::string node : {"server", "w1", "w2"}) {
      addresses_[node] = subnet_ + std::to_string(host);
      const std::string a = tag_ + "a" + std::to_string(host), b = tag_ + "b" + std::to_string(host);
      ++host;
      Ip({"netns", "add", Ns(node)});
      Ip({"link", "add", a, "type", "veth", "peer", "name", b});
      Ip({"link", "set", a, "netns", Ns(node)});
      Ip({"link", "set", b, "netns", Ns("hub")});
      Ip({"-n", Ns("hub"), "link", "set", b, "master", "br0", "up"});
      Ip({"-n", Ns(node), "addr", "add", addresses_[node] + "/24", "dev", a});
      Ip({"-n", Ns(node), "link", "set", a, "up"});
      Ip({"-n", Ns(node), "link", "set", "lo", "up"});
    }
  }

  void TearDown() override {
    if (tag_.empty()) return;  // skipped
    FarmFixture::TearDown();   // processes first, then their namespaces
    for (const std::string node : {"server", "w1", "w2", "hub"}) {
      worker::SpawnOptions o;
      o.argv = {"ip", "netns", "del", Ns(node)};
      worker::ChildProcess::Spawn(o).Wait(std::chrono::seconds(30));
    }
  }

  std::string Ns(const std::string& node) const { return tag_ + "-" + node; }

  void Ip(std::vector<std::string> args) {
    worker::SpawnOptions o;
    o.argv = {"ip"};
    o.argv.insert(o.argv.end(), args.begin(), args.end());
    o.stderr_file = dir_ / "ip.err";
    const auto status = worker::ChildProcess::Spawn(o).Wait(std::chrono::seconds(30));
    std::string cmd;
    for (const auto& a : o.argv) cmd += a + " ";
    ASSERT_TRUE(status && status->ok()) << cmd << ": " << ReadText(dir_ / "ip.err");
  }

  std::vector<std::string> Prefix(const std::string& node) const override {
    return {"ip", "netns", "exec", Ns(node)};
  }

  // The server listens on its address; workers also name the server as their peer. Nothing
  // else: no multicast, no shared loopback.
  std::vector<std::string> BusArgs(const std::string& node) const override {
    if (node == "server") return {"--interface", addresses_.at("server")};
    return {"--interface", addresses_.at(node), "--server-host", addresses_.at("server")};
  }

  // Runs `fn` on a thread that has joined the node's network namespace (the HTTP API binds the
  // server's own loopback).
  void InNamespace(const std::string& node, const std::function<void()>& fn) {
    std::exception_ptr error;
    std::thread t([&] {
      try {
        const int fd = open(("/var/run/netns/" + Ns(node)).c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0 || setns(fd, CLONE_NEWNET) != 0) throw std::runtime_error("setns failed");
        close(fd);
        fn();
      } catch (...) {
        error = std::current_exception();
      }
    });
    t.join();
    if (error) std::rethrow_exception(error);
  }

  std::string tag_;
  std::string subnet_;
  std::map<std::string, std::string> addresses_;
};

TEST_F(NetnsFarm, ServerAndWorkersOnSeparateHostsRunAJobToCompletion) {
  StartServer("server");
  StartWorker("w1", 1, /*episode_s=*/0.5);
  StartWorker("w2", 1, /*episode_s=*/0.5);
  InNamespace("server", [&] {
    api::FarmClient client(url_);
    ASSERT_TRUE(Eventually([&] { return client.Workers().size() == 2; }, 60s))
        << "workers in other namespaces were not discovered";
    const std::string job = client.Submit(Job(/*seeds=*/2), "netns.yaml").job_id;
    ASSERT_TRUE(Eventually([&] { return client.Status(job).terminal(); }, 120s));
    ExpectExactlyOneResultPerEpisode(client, job, 8);
    std::set<std::string> workers;
    for (const auto& r : client.Results(job)) workers.insert(r["worker"].get<std::string>());
    EXPECT_EQ(workers, (std::set<std::string>{"w1", "w2"})) << "both hosts should have worked";
  });
}

}  // namespace
}  // namespace enavi::testing
