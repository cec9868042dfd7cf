#include "api/dds.h"

#include <string>

#include <gtest/gtest.h>

#include "dds_probe.h"
#include "tests/unit/api/cyclone_log_guard.h"
#include "tests/unit/api/farm_test_util.h"

namespace enavi::api::dds {
namespace {

using namespace std::chrono_literals;

// Participant, topic, writer and reader on a private loopback domain; any Cyclone warning while
// it lives fails the test.
struct Loop {
  explicit Loop(const api::BusOptions& bus = testing::TestBus())
      : participant(Domain::Acquire(bus.domain_id, bus.config_xml)),
        topic(participant, &enavi_test_Probe_desc, "probe", Qos().Reliable().KeepLast(8)),
        publisher(participant, Qos().Partition(bus.partition)),
        subscriber(participant, Qos().Partition(bus.partition)),
        writer(publisher, topic, Qos().Reliable().KeepLast(8)),
        reader(subscriber, topic, Qos().Reliable().KeepLast(8)) {}
  testing::CycloneLogGuard cyclone_log;
  Participant participant;
  Topic topic;
  Publisher publisher;
  Subscriber subscriber;
  Writer<enavi_test_Probe> writer;
  Reader<enavi_test_Probe> reader;
};

TEST(DdsCheckTest, NegativeReturnCodeThrowsWithCallAndReason) {
  try {
    Check(DDS_RETCODE_BAD_PARAMETER, "dds_frobnicate");
    FAIL() << "no exception";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.code(), DDS_RETCODE_BAD_PARAMETER);
    EXPECT_EQ(std::string(e.what()), std::string("dds_frobnicate: ") +
                                         dds_strretcode(DDS_RETCODE_BAD_PARAMETER));
  }
  EXPECT_EQ(Check(7, "positive handles pass through"), 7);
}

TEST(DdsDomainTest, OutOfRangeDomainIdThrows) {
  EXPECT_THROW(Domain::Acquire(233, ""), DdsError);
}

TEST(DdsDomainTest, MalformedConfigurationThrows) {
  // An element Cyclone does not know: domain creation must fail, not be ignored.
  EXPECT_THROW(Domain::Acquire(231, "<CycloneDDS><Domain><Nonsense>1</Nonsense></Domain></CycloneDDS>"),
               DdsError);
}

TEST(DdsDomainTest, SameDomainIdIsSharedWithinAProcess) {
  const auto bus = testing::TestBus();
  auto a = Domain::Acquire(bus.domain_id, bus.config_xml);
  auto b = Domain::Acquire(bus.domain_id, bus.config_xml);
  EXPECT_EQ(a.get(), b.get()) << "a second dds_create_domain for the id would fail";
}

TEST(DdsTopicTest, InvalidTopicNameThrows) {
  const auto bus = testing::TestBus();
  Participant participant(Domain::Acquire(bus.domain_id, bus.config_xml));
  try {
    Topic topic(participant, &enavi_test_Probe_desc, "not a valid name!", Qos());
    FAIL() << "topic accepted";
  } catch (const DdsError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("dds_create_topic(not a valid name!): ", 0), 0u) << e.what();
  }
}

TEST(DdsEntityTest, DeletingTheParticipantDeletesItsChildren) {
  Loop loop;
  dds_delete(loop.participant.get());
  enavi_test_Probe sample{1, const_cast<char*>("x"), {0, 0, nullptr, false}};
  try {
    loop.writer.Write(sample);
    FAIL() << "wrote through a deleted writer";
  } catch (const DdsError& e) {
    EXPECT_LT(e.code(), 0);
    EXPECT_EQ(std::string(e.what()).rfind("dds_write: ", 0), 0u) << e.what();
  }
  // The wrappers' destructors now delete handles that are already gone: harmless.
}

TEST(DdsEntityTest, MovedFromEntityOwnsNothing) {
  const auto bus = testing::TestBus();
  auto domain = Domain::Acquire(bus.domain_id, bus.config_xml);
  Entity a(Check(dds_create_participant(bus.domain_id, nullptr, nullptr), "participant"));
  const dds_entity_t handle = a.get();
  Entity b(std::move(a));
  EXPECT_EQ(a.get(), 0);
  EXPECT_EQ(b.get(), handle);
  b.Reset();
  EXPECT_LT(dds_get_parent(handle), 0) << "Reset() deleted the entity";
}

TEST(DdsRoundTripTest, WaitSetWakesOnDataAndReaderTakesIt) {
  Loop loop;
  ReadCondition ready(loop.reader.get());
  GuardCondition guard(loop.participant);
  WaitSet waitset(loop.participant);
  waitset.Attach(ready.get(), 1);
  waitset.Attach(guard.get(), 2);
  ASSERT_TRUE(testing::WaitFor([&] { return loop.writer.MatchedReaders() == 1; }));

  double values[] = {1.5, 2.5, 3.5};
  enavi_test_Probe sample{42, const_cast<char*>("hello"), {3, 3, values, false}};
  loop.writer.Write(sample);
  std::vector<dds_attach_t> triggered;
  ASSERT_TRUE(testing::WaitFor([&] {
    triggered = waitset.Wait(100ms);
    return !triggered.empty();
  }));
  EXPECT_EQ(triggered.front(), 1);
  int seen = 0;
  loop.reader.Take(16, [&](const enavi_test_Probe& p, const SampleInfo& info) {
    ASSERT_TRUE(info.valid_data);
    EXPECT_EQ(p.id, 42);
    EXPECT_STREQ(p.text, "hello");
    ASSERT_EQ(p.values._length, 3u);
    EXPECT_EQ(p.values._buffer[2], 3.5);
    ++seen;
  });
  EXPECT_EQ(seen, 1);

  // Disposing the instance arrives as a not-alive notification for the same key.
  loop.writer.Dispose(sample);
  bool disposed = false;
  ASSERT_TRUE(testing::WaitFor([&] {
    loop.reader.Take(16, [&](const enavi_test_Probe& p, const SampleInfo& info) {
      if (!info.alive && p.id == 42) disposed = true;
    });
    return disposed;
  }));
}

TEST(DdsRoundTripTest, GuardConditionWakesTheWaitSet) {
  Loop loop;
  GuardCondition guard(loop.participant);
  WaitSet waitset(loop.participant);
  waitset.Attach(guard.get(), 7);
  EXPECT_TRUE(waitset.Wait(1ms).empty()) << "nothing triggered yet";
  guard.Trigger();
  const auto triggered = waitset.Wait(10s);
  ASSERT_EQ(triggered.size(), 1u);
  EXPECT_EQ(triggered.front(), 7);
  EXPECT_TRUE(guard.TakeTriggered());
  EXPECT_FALSE(guard.TakeTriggered()) << "taking resets the trigger";
}

TEST(DdsRoundTripTest, DifferentPartitionsDoNotMatch) {
  auto bus_a = testing::TestBus();
  auto bus_b = bus_a;
  bus_b.partition += "-other";
  Loop a(bus_a), b(bus_b);
  // Same domain and topic, different partitions: each writer matches only its own reader.
  ASSERT_TRUE(testing::WaitFor([&] { return a.writer.MatchedReaders() == 1; }));
  ASSERT_TRUE(testing::WaitFor([&] { return b.writer.MatchedReaders() == 1; }));
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(a.writer.MatchedReaders(), 1u);
  EXPECT_EQ(b.reader.MatchedWriters(), 1u);
}

}  // namespace
}  // namespace enavi::api::dds
