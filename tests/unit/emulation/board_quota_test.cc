#include "workers/emulation/board_quota.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace enavi::emulation {
namespace {

TEST(BoardQuotaTest, BoardCapIsCoresTimesSpeedOverDilation) {
  QuotaOptions o;
  o.dilation = 2.0;
  o.period_us = 10'000;
  const BoardQuota q = ComputeBoardQuota({4, 0.4}, o);
  EXPECT_EQ(q.board_quota_us, 8'000) << "4 x 0.4 / 2 = 0.8 host CPUs of a 10 ms period";
  EXPECT_DOUBLE_EQ(q.BoardCpus(), 0.8);
}

TEST(BoardQuotaTest, ThreadCapIsOneBoardCoreSoSlowCoresStaySlow) {
  // Six slow cores have lots of capacity, but a single thread must still run at one core's
  // speed: the per-thread quota is speed / k whatever the core count.
  QuotaOptions o;
  o.dilation = 1.0;
  const BoardQuota q = ComputeBoardQuota({6, 0.25}, o);
  EXPECT_DOUBLE_EQ(q.CoreCpus(), 0.25);
  EXPECT_DOUBLE_EQ(q.BoardCpus(), 1.5);
  EXPECT_DOUBLE_EQ(ExpectedSlowdown(q, 1, 2.0), 4.0) << "one thread: k / speed";
}

TEST(BoardQuotaTest, ExpectedSlowdownFollowsTheBindingCap) {
  QuotaOptions o;
  o.dilation = 2.0;
  const BoardQuota q = ComputeBoardQuota({4, 0.5}, o);  // core 0.25, board 1.0 host CPUs
  EXPECT_DOUBLE_EQ(ExpectedSlowdown(q, 4, 2.0), 4.0) << "one thread per core: k / speed";
  EXPECT_DOUBLE_EQ(ExpectedSlowdown(q, 8, 2.0), 8.0) << "8 threads share the 1.0 CPU board cap";
  EXPECT_DOUBLE_EQ(ExpectedSlowdown(q, 16, 2.0), 16.0);
  const BoardQuota fast = ComputeBoardQuota({4, 1.0}, {});  // 4 host CPUs wanted, 2 exist
  EXPECT_DOUBLE_EQ(ExpectedSlowdown(fast, 4, 2.0), 2.0) << "the host becomes the cap";
}

TEST(BoardQuotaTest, QuotasAreRoundedToWholeMicroseconds) {
  QuotaOptions o;
  o.period_us = 20'000;
  o.dilation = 3.0;
  const BoardQuota q = ComputeBoardQuota({3, 0.55}, o);
  EXPECT_EQ(q.core_quota_us, 3'667);   // 0.55 / 3 x 20000 = 3666.67
  EXPECT_EQ(q.board_quota_us, 11'000);  // 3 x 0.55 / 3 x 20000
  EXPECT_NEAR(q.CoreCpus(), 0.55 / 3.0, 0.5 / 20'000.0);
}

TEST(BoardQuotaTest, OutOfRangeInputsNameTheFieldAndRange) {
  QuotaOptions o;
  auto message = [](auto fn) {
    try {
      fn();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message([&] { ComputeBoardQuota({0, 0.5}, o); }).find("cores"), std::string::npos);
  EXPECT_NE(message([&] { ComputeBoardQuota({2, 1.5}, o); }).find("dilation must be >= the board's core speed 1.5"),
            std::string::npos);
  EXPECT_NE(message([&] { ComputeBoardQuota({2, 0.0}, o); }).find("core_speed"), std::string::npos);
  o.dilation = 0.5;
  EXPECT_NE(message([&] { ComputeBoardQuota({2, 0.5}, o); }).find("dilation"), std::string::npos);
  o.dilation = 1.0;
  o.period_us = 500;
  EXPECT_NE(message([&] { ComputeBoardQuota({2, 0.5}, o); }).find("[1000, 1000000]"),
            std::string::npos);
}

TEST(BoardQuotaTest, PerThreadQuotaBelowKernelMinimumSuggestsAPeriod) {
  QuotaOptions o;
  o.dilation = 4.0;
  o.period_us = 10'000;  // 0.2 / 4 x 10 ms = 500 us < 1000 us
  try {
    ComputeBoardQuota({4, 0.2}, o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("period_us >= 20000"), std::string::npos) << e.what();
  }
  o.period_us = 20'000;
  EXPECT_EQ(ComputeBoardQuota({4, 0.2}, o).core_quota_us, kMinQuotaUs);
}

TEST(BoardQuotaTest, HostUtilisationScalesToBoardCores) {
  QuotaOptions o;
  o.dilation = 2.0;
  const BoardQuota q = ComputeBoardQuota({4, 0.25}, o);  // a thread gets 0.125 host CPU
  EXPECT_DOUBLE_EQ(HostToBoardPercent(12.5, q), 100.0) << "always busy = one whole board core";
  EXPECT_DOUBLE_EQ(HostToBoardPercent(6.25, q), 50.0);
}

TEST(BoardQuotaTest, MinimumDilationFitsTheBoardIntoFreeHostCpus) {
  EXPECT_DOUBLE_EQ(MinimumDilation({4, 0.3}, 1.75), 1.0) << "1.2 CPUs fit without dilation";
  EXPECT_DOUBLE_EQ(MinimumDilation({6, 0.6}, 1.75), 2.25) << "3.6 / 1.75 = 2.06 -> 2.25";
  EXPECT_DOUBLE_EQ(MinimumDilation({4, 0.5}, 1.0), 2.0);
  EXPECT_THROW(MinimumDilation({4, 0.5}, 0.0), std::invalid_argument);
}

TEST(BoardQuotaTest, ABoardFasterThanTheHostIsEmulatedByDilatingTimeAtLeastByItsSpeed) {
  EXPECT_DOUBLE_EQ(MinimumDilation({1, 1.07}, 1.75), 1.25) << "one core fits, but a thread needs k >= 1.07";
  QuotaOptions o;
  o.dilation = 1.25;
  const BoardQuota q = ComputeBoardQuota({4, 1.07}, o);
  EXPECT_NEAR(q.CoreCpus(), 1.07 / 1.25, 1e-4) << "a board core is 0.856 of a host core in dilated time";
  EXPECT_NEAR(ExpectedSlowdown(q, 1, 4.0), 1.25 / 1.07, 1e-3) << "one thread: k / speed, as for slower boards";
  o.dilation = 1.0;
  EXPECT_THROW(ComputeBoardQuota({4, 1.07}, o), std::invalid_argument) << "one host core cannot run 1.07 of itself";
}

}  // namespace
}  // namespace enavi::emulation
