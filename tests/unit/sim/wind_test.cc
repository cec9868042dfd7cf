// Wind: Dryden statistics of the exactly discretised filters, the 1-cosine gust, validation,
// determinism.

#include "workers/sim/wind.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace enavi::sim {
namespace {

// Sample variance and autocorrelation at `lag` of a long sequence.
struct Stats {
  double var = 0.0, acf = 0.0;
};
Stats Measure(const std::vector<double>& y, int lag) {
  double mean = 0.0;
  for (double v : y) mean += v;
  mean /= y.size();
  Stats s;
  for (std::size_t i = 0; i < y.size(); ++i) s.var += (y[i] - mean) * (y[i] - mean);
  for (std::size_t i = 0; i + lag < y.size(); ++i) s.acf += (y[i] - mean) * (y[i + lag] - mean);
  s.acf /= (y.size() - lag);
  s.var /= y.size();
  s.acf /= s.var;
  return s;
}

TEST(DrydenTransverseStep, UnitVarianceAndDrydenAutocorrelationForCoarseAndFineSteps) {
  // R(tau) / sigma^2 = (1 - a tau / 2) e^{-a tau} for the transverse Dryden spectrum.
  for (double dt : {0.001, 0.05}) {
    const double a = 2.0;  // V / L, 1/s
    navstack::rl::Rng rng(7);
    Eigen::Vector2d x = Eigen::Vector2d::Zero();
    std::vector<double> y;
    const int n = dt < 0.01 ? 2000000 : 400000;
    for (int i = 0; i < n; ++i) {
      const double n1 = rng.Normal(), n2 = rng.Normal();
      y.push_back(DrydenTransverseStep(&x, a, dt, n1, n2));
    }
    const int lag = static_cast<int>(std::round(0.5 / dt));  // tau = 0.5 s
    const Stats s = Measure(y, lag);
    const double tau = lag * dt;
    EXPECT_NEAR(s.var, 1.0, 0.06) << "dt " << dt;
    EXPECT_NEAR(s.acf, (1.0 - a * tau / 2.0) * std::exp(-a * tau), 0.05) << "dt " << dt;
  }
}

TEST(WindField, TurbulenceHasTheStandardsIntensitiesAlongWindAcrossAndVertical) {
  api::WindSpec o;
  o.speed_mps = 5.0;
  o.direction_deg = 90.0;  // blowing toward +y: u along y, v along -x
  o.turbulence = "severe";
  WindField wind(o, 0.01, 3);
  const double h = 2.0;
  std::vector<double> ux, uy, uz;
  for (int i = 0; i < 400000; ++i) {
    const Eigen::Vector3d a = wind.Step(h, Eigen::Vector3d::Zero());
    ux.push_back(a.x());
    uy.push_back(a.y());
    uz.push_back(a.z());
  }
  const Eigen::Vector3d sigma = WindField::Intensities(Turbulence::kSevere, h);
  EXPECT_NEAR(std::sqrt(Measure(uy, 1).var), sigma(0), 0.08 * sigma(0));
  EXPECT_NEAR(std::sqrt(Measure(ux, 1).var), sigma(1), 0.08 * sigma(1));
  EXPECT_NEAR(std::sqrt(Measure(uz, 1).var), sigma(2), 0.08 * sigma(2));
  double mean_y = 0.0;
  for (double v : uy) mean_y += v;
  EXPECT_NEAR(mean_y / uy.size(), 5.0, 0.3);
}

TEST(WindField, LowAltitudeScaleLengthsAndIntensitiesFollowMilF8785C) {
  // h = 100 ft: L_u = 100 / (0.177 + 0.0823)^1.2 ft, L_w = 100 ft; sigma_w = 0.1 W20.
  const double h = 100.0 * 0.3048;
  const Eigen::Vector3d L = WindField::ScaleLengths(h);
  EXPECT_NEAR(L(0), 100.0 / std::pow(0.2593, 1.2) * 0.3048, 1e-9);
  EXPECT_NEAR(L(2), h, 1e-12);
  const Eigen::Vector3d s = WindField::Intensities(Turbulence::kModerate, h);
  EXPECT_NEAR(s(2), 0.1 * 30.0 * 1852.0 / 3600.0, 1e-12);
  EXPECT_NEAR(s(0), s(2) / std::pow(0.2593, 0.4), 1e-12);
  EXPECT_EQ(WindField::Intensities(Turbulence::kNone, h), Eigen::Vector3d::Zero());
  // Light < moderate < severe.
  EXPECT_LT(TurbulenceW20(Turbulence::kLight), TurbulenceW20(Turbulence::kModerate));
  EXPECT_LT(TurbulenceW20(Turbulence::kModerate), TurbulenceW20(Turbulence::kSevere));
}

TEST(WindField, OneMinusCosineGustRisesHoldsAndFalls) {
  const api::GustSpec g{.start_s = 1.0, .rise_s = 2.0, .hold_s = 1.0, .speed_mps = 6.0, .direction_deg = 0};
  EXPECT_EQ(WindField::GustSpeed(g, 0.5), 0.0);
  EXPECT_NEAR(WindField::GustSpeed(g, 2.0), 3.0, 1e-12);  // half way up
  EXPECT_NEAR(WindField::GustSpeed(g, 3.5), 6.0, 1e-12);
  EXPECT_NEAR(WindField::GustSpeed(g, 5.0), 3.0, 1e-12);  // half way down
  EXPECT_EQ(WindField::GustSpeed(g, 7.0), 0.0);
  api::WindSpec o;
  o.gust = g;
  WindField wind(o, 0.5, 1);
  Eigen::Vector3d a;
  for (int i = 0; i < 7; ++i) a = wind.Step(2.0, Eigen::Vector3d::Zero());  // t = 3.5
  EXPECT_NEAR(a.x(), 6.0, 1e-12);
  EXPECT_NEAR(a.y(), 0.0, 1e-12);
}

TEST(WindField, SameSeedSameAirDifferentSeedDifferentAir) {
  api::WindSpec o;
  o.turbulence = "light";
  WindField a(o, 0.001, 11), b(o, 0.001, 11), c(o, 0.001, 12);
  bool differs = false;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d v(0.5, 0.0, 0.0);
    const Eigen::Vector3d wa = a.Step(1.5, v), wb = b.Step(1.5, v), wc = c.Step(1.5, v);
    ASSERT_EQ(wa, wb);
    differs |= (wa != wc);
  }
  EXPECT_TRUE(differs);
}

TEST(WindField, RejectsBadValuesNamingTheField) {
  const auto message = [](const api::WindSpec& o) {
    try {
      WindField w(o, 0.001, 1);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  api::WindSpec o;
  o.speed_mps = -1.0;
  EXPECT_EQ(message(o).rfind("wind.speed_mps:", 0), 0u) << message(o);
  o = {};
  o.direction_deg = std::nan("");
  EXPECT_EQ(message(o).rfind("wind.direction_deg:", 0), 0u) << message(o);
  o = {};
  o.gust.rise_s = 0.0;
  EXPECT_EQ(message(o).rfind("wind.gust.rise_s:", 0), 0u) << message(o);
  o = {};
  o.turbulence = "strong";
  EXPECT_EQ(message(o).rfind("wind.turbulence:", 0), 0u) << message(o);
  o = {};
  o.gust.speed_mps = 41.0;
  EXPECT_EQ(message(o).rfind("wind.gust.speed_mps:", 0), 0u) << message(o);
  EXPECT_EQ(message(api::WindSpec{}), "accepted");
  EXPECT_THROW(ParseTurbulence("strong"), std::invalid_argument);
  // Every level the spec accepts is a severity of the model.
  for (const char* level : api::kTurbulenceLevels) EXPECT_EQ(TurbulenceName(ParseTurbulence(level)), std::string(level));
  EXPECT_EQ(ParseTurbulence("severe"), Turbulence::kSevere);
}

}  // namespace
}  // namespace enavi::sim
