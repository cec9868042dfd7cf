// Policy file: exact round trip, and a clear std::invalid_argument naming the file and the field
// for every kind of damage.

#include "navstack/rl/policy_io.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "navstack/adapt/policy_state.h"

namespace enavi::navstack::rl {
namespace {

using nlohmann::json;

std::string TempPath(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / name).string();
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

// A trained-looking policy: orthogonal weights perturbed by awkward doubles, a non-trivial
// normaliser, metadata.
PolicyFile SamplePolicy() {
  PolicyFile p = MakeFrequencyPolicy(ActionGrid(), 31);
  Rng rng(32);
  for (Eigen::Index i = 0; i < p.net.actor().num_params(); i += 7) {
    p.net.actor().params()[i] += 1e-17 * rng.Normal() + rng.Normal() / 3.0;
  }
  p.net.critic().params()[5] = 1.0 / 3.0;
  p.net.critic().params()[6] = -2.2250738585072014e-308;  // smallest normal double
  p.net.critic().params()[7] = 5e-324;                    // a subnormal
  Eigen::MatrixXd X(kPolicyStateDim, 40);
  for (int j = 0; j < 40; ++j) {
    for (int k = 0; k < kPolicyStateDim; ++k) X(k, j) = rng.Normal() * 0.1 + 0.3;
  }
  p.net.normaliser().Update(X);
  p.metadata = {{"command", "enavi train --seed 1"}, {"iterations", 3}};
  return p;
}

TEST(PolicyIoTest, RoundTripIsBitExact) {
  const PolicyFile p = SamplePolicy();
  const std::string path = TempPath("policy_roundtrip.json");
  SavePolicyFile(path, p);
  const PolicyFile q = LoadFrequencyPolicy(path);
  EXPECT_TRUE(q.net.actor().params() == p.net.actor().params()) << "bitwise";
  EXPECT_TRUE(q.net.critic().params() == p.net.critic().params());
  EXPECT_TRUE(q.net.normaliser().mean == p.net.normaliser().mean);
  EXPECT_TRUE(q.net.normaliser().var == p.net.normaliser().var);
  EXPECT_EQ(q.net.normaliser().count, p.net.normaliser().count);
  EXPECT_EQ(q.net.config().hidden, p.net.config().hidden);
  ASSERT_TRUE(q.action_grid.has_value());
  EXPECT_TRUE(*q.action_grid == *p.action_grid);
  EXPECT_EQ(q.feature_names, PolicyStateFeatureNames());
  EXPECT_EQ(q.metadata, p.metadata);
  // Saving what was loaded writes the same bytes.
  const std::string path2 = TempPath("policy_roundtrip2.json");
  SavePolicyFile(path2, q);
  EXPECT_EQ(ReadText(path), ReadText(path2));
  std::remove(path.c_str());
  std::remove(path2.c_str());
}

// Saves SamplePolicy, applies `damage` to its JSON (or text), and expects LoadFrequencyPolicy to
// throw std::invalid_argument whose message names the file and contains `field`.
void ExpectRefused(const std::string& name, const std::function<void(json&)>& damage,
                   const std::string& field) {
  const std::string path = TempPath("policy_" + name + ".json");
  json j = PolicyToJson(SamplePolicy());
  damage(j);
  WriteText(path, j.dump());
  try {
    LoadFrequencyPolicy(path);
    ADD_FAILURE() << name << ": the damaged file loaded";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << name << ": " << msg;
    EXPECT_NE(msg.find(field), std::string::npos) << name << ": " << msg;
  }
  std::remove(path.c_str());
}

TEST(PolicyIoTest, MissingFileNamesThePath) {
  const std::string path = TempPath("no_such_policy.json");
  try {
    LoadFrequencyPolicy(path);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
}

TEST(PolicyIoTest, TruncatedFileIsRefused) {
  const std::string path = TempPath("policy_truncated.json");
  SavePolicyFile(path, SamplePolicy());
  const std::string text = ReadText(path);
  WriteText(path, text.substr(0, text.size() * 2 / 3));
  try {
    LoadFrequencyPolicy(path);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
  }
  WriteText(path, "");
  EXPECT_THROW(LoadFrequencyPolicy(path), std::invalid_argument) << "empty file";
  std::remove(path.c_str());
}

TEST(PolicyIoTest, LiteralNaNOrOverflowInTheTextIsRefused) {
  const std::string path = TempPath("policy_nan_text.json");
  std::string text = PolicyToJson(SamplePolicy()).dump();
  const std::size_t pos = text.find("\"bias\":[") + 8;
  WriteText(path, text.substr(0, pos) + "NaN" + text.substr(text.find_first_of(",]", pos)));
  EXPECT_THROW(LoadFrequencyPolicy(path), std::invalid_argument);
  WriteText(path, text.substr(0, pos) + "1e999" + text.substr(text.find_first_of(",]", pos)));
  EXPECT_THROW(LoadFrequencyPolicy(path), std::invalid_argument);
  std::remove(path.c_str());
}

TEST(PolicyIoTest, WrongFormatOrUnknownVersionIsRefused) {
  ExpectRefused("format", [](json& j) { j["format"] = "something-else"; }, "format");
  ExpectRefused("version", [](json& j) { j["version"] = 2; }, "version");
  ExpectRefused("version_type", [](json& j) { j["version"] = "1"; }, "version");
  ExpectRefused("not_object", [](json& j) { j = json::array(); }, "(root)");
}

TEST(PolicyIoTest, MissingFieldsAreNamed) {
  ExpectRefused("no_critic", [](json& j) { j.erase("critic"); }, "critic");
  ExpectRefused("no_bias", [](json& j) { j["actor"]["layers"][1].erase("bias"); },
                "actor.layers[1].bias");
  ExpectRefused("no_normaliser", [](json& j) { j["observation"].erase("normaliser"); },
                "observation.normaliser");
}

TEST(PolicyIoTest, WrongShapesAreNamed) {
  ExpectRefused("row_missing", [](json& j) { j["actor"]["layers"][0]["weights"].erase(3); },
                "actor.layers[0].weights");
  ExpectRefused("row_short", [](json& j) { j["critic"]["layers"][1]["weights"][7].erase(0); },
                "critic.layers[1].weights[7]");
  ExpectRefused("bias_long", [](json& j) { j["actor"]["layers"][2]["bias"].push_back(0.0); },
                "actor.layers[2].bias");
  ExpectRefused("layer_missing", [](json& j) { j["critic"]["layers"].erase(2); }, "critic.layers");
  ExpectRefused("hidden_changed", [](json& j) { j["architecture"]["hidden"][1] = 149; },
                "actor.layers[1].out");
  ExpectRefused("grid_short", [](json& j) { j["action_grid"]["actions"].erase(0); },
                "action_grid.actions");
  ExpectRefused("mean_short", [](json& j) { j["observation"]["normaliser"]["mean"].erase(0); },
                "observation.normaliser.mean");
  ExpectRefused("huge", [](json& j) { j["architecture"]["hidden"] = {60000, 60000}; },
                "architecture");
}

TEST(PolicyIoTest, NonFiniteOrNonNumericValuesAreNamed) {
  // NaN and inf are written as null by JSON serialisers; strings are plain corruption.
  ExpectRefused("null_weight", [](json& j) { j["actor"]["layers"][1]["weights"][2][5] = nullptr; },
                "actor.layers[1].weights[2][5]");
  ExpectRefused("string_bias", [](json& j) { j["critic"]["layers"][0]["bias"][0] = "NaN"; },
                "critic.layers[0].bias[0]");
  ExpectRefused("negative_var", [](json& j) { j["observation"]["normaliser"]["var"][3] = -1.0; },
                "observation.normaliser.var");
  ExpectRefused("bad_action", [](json& j) { j["action_grid"]["actions"][4] = {0, 0, 0}; },
                "action_grid.actions");
}

TEST(PolicyIoTest, PolicyForAnotherObservationLayoutIsRefused) {
  ExpectRefused("features", [](json& j) { j["observation"]["features"][0] = "eci_v2"; },
                "observation.features");
  ExpectRefused("no_grid", [](json& j) { j["action_grid"] = nullptr; }, "action_grid");
}

TEST(PolicyIoTest, GenericPolicyWithoutGridRoundTrips) {
  PolicyFile p{ActorCritic({3, 5, {4}}), {"a", "b", "c"}, std::nullopt, json::object()};
  Rng rng(1);
  p.net.InitializeWeights(&rng);
  const PolicyFile q = PolicyFromJson(PolicyToJson(p), "test");
  EXPECT_FALSE(q.action_grid.has_value());
  EXPECT_TRUE(q.net.actor().params() == p.net.actor().params());
  EXPECT_EQ(q.feature_names, p.feature_names);
}

}  // namespace
}  // namespace enavi::navstack::rl
