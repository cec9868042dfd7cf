#include "api/farm_bus.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/dds_config.h"
#include "tests/unit/api/cyclone_log_guard.h"
#include "tests/unit/api/farm_test_util.h"

namespace enavi::api {
namespace {

using namespace std::chrono_literals;
using testing::TestBus;
using testing::WaitFor;

EpisodeResult SampleResult() {
  EpisodeResult r;
  r.spec.world = "s2";
  r.spec.seed = 7;
  r.spec.board = "tx2";
  r.spec.method = "enavi";
  r.scenario = "s2";
  r.success = true;
  r.end_reason = "goal_reached";
  r.flight_time_s = 31.5;
  r.path_length_m = 50.25;
  r.nav_cpu_util_pct = 88.0;
  r.task_cpu_util_pct = {{"perception", 40}, {"planning", 30}, {"collision", 10}, {"difference", 8}};
  r.notes["clock"] = "virtual";
  r.events = {{1.0, "replan", "trigger"}, {2.5, "deadline_miss", "perception"}};
  for (int i = 0; i < 5; ++i) {
    r.series.t.push_back(0.1 * i);
    r.series.position.push_back({1.0 * i, 2.0 * i, 3.0});
    r.series.velocity.push_back({0.5, 0.0, -0.1 * i});
    r.series.eci.push_back(0.2 * i);
    r.series.f_per.push_back(30);
    r.series.f_col.push_back(15);
    r.series.f_dif.push_back(10);
    r.series.res.push_back(0.1);
    r.series.utilisation.push_back(80 + i);
  }
  return r;
}

// Drains the server bus until `pred` holds on what has arrived.
struct ServerInbox {
  std::vector<WorkerStatus> statuses;
  std::vector<std::string> gone, left;
  std::vector<ResultMessage> results;
  void Pump(ServerBus& bus) {
    auto in = bus.Wait(20ms);
    for (auto& s : in.statuses) statuses.push_back(std::move(s));
    for (auto& g : in.workers_gone) gone.push_back(std::move(g));
    for (auto& g : in.workers_left) left.push_back(std::move(g));
    for (auto& r : in.results) results.push_back(std::move(r));
    for (const auto& b : in.bad_samples) ADD_FAILURE() << "bad sample: " << b;
  }
};

struct WorkerInbox {
  std::vector<Assignment> assignments;
  std::vector<ResultAck> acks;
  std::vector<JobEvent> events;
  void Pump(WorkerBus& bus) {
    auto in = bus.Wait(20ms);
    for (auto& a : in.assignments) assignments.push_back(std::move(a));
    for (auto& a : in.acks) acks.push_back(std::move(a));
    for (auto& e : in.events) events.push_back(std::move(e));
    for (const auto& b : in.bad_samples) ADD_FAILURE() << "bad sample: " << b;
  }
};

// Every bus test fails on a Cyclone warning or error.
class FarmBusTest : public ::testing::Test {
 protected:
  testing::CycloneLogGuard cyclone_log_;
};

TEST_F(FarmBusTest, WorkerStatusReachesTheServerWithEveryField) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  WorkerBus worker(bus, "w1");
  WorkerStatus s;
  s.worker_id = "w1";
  s.host = "hostA";
  s.pid = 1234;
  s.slots = 4;
  s.free_slots = 3;
  s.boards = {"tx2", "nx"};
  s.clocks = {"virtual"};
  s.calibration_id = "cal-7";
  s.seq = 9;
  s.running = {{"j1-00001", 2}};
  s.unacked_results = 1;
  s.version = "0.1.0";
  worker.Publish(s);
  ServerInbox in;
  ASSERT_TRUE(WaitFor([&] { in.Pump(server); return !in.statuses.empty(); }));
  const WorkerStatus& got = in.statuses.back();
  EXPECT_EQ(got.worker_id, "w1");
  EXPECT_EQ(got.host, "hostA");
  EXPECT_EQ(got.slots, 4);
  EXPECT_EQ(got.free_slots, 3);
  EXPECT_EQ(got.boards, s.boards);
  EXPECT_EQ(got.calibration_id, "cal-7");
  EXPECT_EQ(got.seq, 9u);
  ASSERT_EQ(got.running.size(), 1u);
  EXPECT_EQ(got.running[0], (EpisodeRef{"j1-00001", 2}));
  EXPECT_EQ(got.protocol, kFarmProtocolVersion);
}

TEST_F(FarmBusTest, AssignmentsReachOnlyTheirWorker) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  WorkerBus a(bus, "a"), b(bus, "b");
  ASSERT_TRUE(WaitFor([&] { return a.MatchedServers() == 1 && b.MatchedServers() == 1; }));
  Assignment assignment;
  assignment.worker_id = "b";
  assignment.episode_id = "j1-00003";
  assignment.attempt = 1;
  assignment.job_id = "j1";
  assignment.lease_ms = 15000;
  assignment.spec.board = "pi4b";
  assignment.spec.seed = 3;
  assignment.spec.overrides["f_per_max"] = 12.5;
  server.Publish(assignment);
  WorkerInbox in_a, in_b;
  ASSERT_TRUE(WaitFor([&] { in_b.Pump(b); return !in_b.assignments.empty(); }));
  in_a.Pump(a);
  EXPECT_TRUE(in_a.assignments.empty()) << "worker a got b's assignment";
  const Assignment& got = in_b.assignments.front();
  EXPECT_EQ(got.episode_id, "j1-00003");
  EXPECT_EQ(got.spec.board, "pi4b");
  EXPECT_EQ(got.spec.overrides.at("f_per_max"), 12.5);
}

TEST_F(FarmBusTest, ResultWithTimeSeriesRoundTripsAndAckComesBack) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  WorkerBus worker(bus, "w1");
  ResultMessage m;
  m.episode_id = "j1-00000";
  m.attempt = 1;
  m.worker_id = "w1";
  m.job_id = "j1";
  m.wall_time_s = 2.5;
  m.result = SampleResult();
  ASSERT_TRUE(WaitFor([&] { return worker.MatchedServers() == 1; }));
  worker.Publish(m);
  ServerInbox in;
  ASSERT_TRUE(WaitFor([&] { in.Pump(server); return !in.results.empty(); }));
  const ResultMessage& got = in.results.front();
  EXPECT_EQ(got.status, ResultStatus::kOk);
  EXPECT_EQ(got.wall_time_s, 2.5);
  // The whole record survives: compare the JSON of both.
  EXPECT_EQ(nlohmann::json(got.result).dump(), nlohmann::json(m.result).dump());

  server.Publish(ResultAck{"w1", "j1-00000", 1, AckStatus::kStored, ""});
  WorkerInbox win;
  ASSERT_TRUE(WaitFor([&] { win.Pump(worker); return !win.acks.empty(); }));
  EXPECT_EQ(win.acks.front().status, AckStatus::kStored);
  EXPECT_EQ(win.acks.front().episode_id, "j1-00000");
}

TEST_F(FarmBusTest, UnacknowledgedResultReachesAServerThatStartsLater) {
  const BusOptions bus = TestBus();
  WorkerBus worker(bus, "w1");
  ResultMessage m;
  m.episode_id = "j1-00004";
  m.attempt = 2;
  m.worker_id = "w1";
  m.job_id = "j1";
  m.result = SampleResult();
  worker.Publish(m);  // no server yet
  // A server (re)starting now still gets it: the result writer keeps it (transient-local).
  ServerBus server(bus);
  ServerInbox in;
  ASSERT_TRUE(WaitFor([&] { in.Pump(server); return !in.results.empty(); }));
  EXPECT_EQ(in.results.front().episode_id, "j1-00004");
  EXPECT_EQ(in.results.front().attempt, 2);

  // Once retired (after the ack) a further server start does not see it again.
  worker.Retire(m);
  ServerBus later(bus);
  ServerInbox in2;
  ASSERT_TRUE(WaitFor([&] { return later.MatchedWorkers() == 1; }));
  const auto until = std::chrono::steady_clock::now() + 500ms;
  while (std::chrono::steady_clock::now() < until) in2.Pump(later);
  EXPECT_TRUE(in2.results.empty()) << "a retired result was replayed";
}

TEST_F(FarmBusTest, GracefulLeaveAndVanishedWorkerAreToldApart) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  ServerInbox in;
  {
    WorkerBus polite(bus, "polite");
    WorkerStatus s;
    s.worker_id = "polite";
    polite.Publish(s);
    ASSERT_TRUE(WaitFor([&] { in.Pump(server); return !in.statuses.empty(); }));
    polite.DisposeStatus();
    ASSERT_TRUE(WaitFor([&] { in.Pump(server); return !in.left.empty(); }));
    EXPECT_EQ(in.left.front(), "polite");
  }
  EXPECT_TRUE(std::find(in.gone.begin(), in.gone.end(), "polite") == in.gone.end())
      << "a graceful leave is not a crash";
  {
    auto vanishing = std::make_unique<WorkerBus>(bus, "vanishing");
    WorkerStatus s;
    s.worker_id = "vanishing";
    vanishing->Publish(s);
    ASSERT_TRUE(WaitFor([&] {
      in.Pump(server);
      return std::any_of(in.statuses.begin(), in.statuses.end(),
                         [](const WorkerStatus& x) { return x.worker_id == "vanishing"; });
    }));
    vanishing.reset();  // its writers disappear without a dispose
  }
  ASSERT_TRUE(WaitFor([&] {
    in.Pump(server);
    return std::find(in.gone.begin(), in.gone.end(), "vanishing") != in.gone.end();
  }));
}

TEST_F(FarmBusTest, JobEventsAreBroadcast) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  WorkerBus a(bus, "a"), b(bus, "b");
  ASSERT_TRUE(WaitFor([&] { return a.MatchedServers() == 1 && b.MatchedServers() == 1; }));
  // Job events have their own writer: wait until both workers' event readers matched too.
  std::this_thread::sleep_for(200ms);
  server.Publish(JobEvent{"j9", "cancelled", "", 1, 0, 4, "job cancelled", 1});
  WorkerInbox in_a, in_b;
  ASSERT_TRUE(WaitFor([&] {
    in_a.Pump(a);
    in_b.Pump(b);
    return !in_a.events.empty() && !in_b.events.empty();
  }));
  EXPECT_EQ(in_a.events.front().kind, "cancelled");
  EXPECT_EQ(in_b.events.front().job_id, "j9");
}

TEST_F(FarmBusTest, WakeInterruptsAWait) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  std::thread waker([&] {
    std::this_thread::sleep_for(50ms);
    server.Wake();
  });
  const auto start = std::chrono::steady_clock::now();
  server.Wait(60s);
  waker.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, 30s) << "Wake() did not end the wait";
}

TEST(CycloneConfigTest, LoopbackConfigUsesOnlyTheLoopbackInterface) {
  DdsNetwork net;
  net.loopback = true;
  net.peers = {"ignored.example"};
  const std::string xml = CycloneConfigXml(net);
  EXPECT_NE(xml.find("<NetworkInterface address=\"127.0.0.1\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<Peer address=\"127.0.0.1\"/>"), std::string::npos) << xml;
  EXPECT_EQ(xml.find("ignored.example"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find("<ParticipantIndex>auto</ParticipantIndex>"), std::string::npos);
  // A lost peer ages out in 5 s, and no writer blocks on what it leaves unacknowledged.
  EXPECT_NE(xml.find("<LeaseDuration>5s</LeaseDuration>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<WhcHigh>16384kB</WhcHigh><WhcAdaptive>false</WhcAdaptive>"), std::string::npos) << xml;
}

TEST(CycloneConfigTest, PeersAndInterfaceAreWrittenAndLocalhostAdded) {
  DdsNetwork net;
  net.peers = {"10.0.0.1", "farm-server"};
  net.interface = "eth0";
  const std::string xml = CycloneConfigXml(net);
  EXPECT_NE(xml.find("<NetworkInterface name=\"eth0\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<Peer address=\"10.0.0.1\"/>"), std::string::npos);
  EXPECT_NE(xml.find("<Peer address=\"farm-server\"/>"), std::string::npos);
  EXPECT_NE(xml.find("<Peer address=\"localhost\"/>"), std::string::npos);
}

TEST(CycloneConfigTest, PeerThatCouldInjectXmlIsRejected) {
  DdsNetwork net;
  net.peers = {"a\"/><Evil/>"};
  try {
    CycloneConfigXml(net);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("peers: ", 0), 0u) << e.what();
  }
  net.peers.clear();
  net.max_participants_per_host = 500;
  EXPECT_THROW(CycloneConfigXml(net), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::api
