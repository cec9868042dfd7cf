// Policy file: float32 storage that round-trips exactly, float64 documents that are bit-exact,
// version 1 files that still load, and a clear std::invalid_argument naming the file and the
// field for every kind of damage.

#include "navstack/rl/policy_io.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "api/base64.h"
#include "api/content_hash.h"
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

// Every weight of `p` rounded to float32: what a policy file stores.
PolicyFile RoundedToFloat32(PolicyFile p) {
  for (Mlp* mlp : {&p.net.actor(), &p.net.critic()}) {
    for (Eigen::Index i = 0; i < mlp->num_params(); ++i) {
      mlp->params()[i] = static_cast<double>(static_cast<float>(mlp->params()[i]));
    }
  }
  return p;
}

TEST(PolicyIoTest, FileStoresFloat32WeightsAndRoundTripsThemExactly) {
  const PolicyFile p = SamplePolicy();
  const std::string path = TempPath("policy_roundtrip.json");
  SavePolicyFile(path, p);
  const PolicyFile q = LoadFrequencyPolicy(path);
  const PolicyFile expected = RoundedToFloat32(p);
  EXPECT_TRUE(q.net.actor().params() == expected.net.actor().params()) << "bitwise";
  EXPECT_TRUE(q.net.critic().params() == expected.net.critic().params());
  EXPECT_FALSE(q.net.actor().params() == p.net.actor().params()) << "the sample has non-float32 weights";
  EXPECT_EQ(q.net.critic().params()[7], 0.0) << "a double subnormal is 0 in float32";
  // The normaliser stays in double.
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
  // One line of JSON, 4 bytes a weight in base64 plus a small header.
  const std::string text = ReadText(path);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1);
  const auto weights = p.net.actor().num_params() + p.net.critic().num_params();
  EXPECT_LT(text.size(), weights * 4 * 4 / 3 + 20000);
  std::remove(path.c_str());
  std::remove(path2.c_str());
}

TEST(PolicyIoTest, Float64DocumentIsBitExact) {
  const PolicyFile p = SamplePolicy();
  const PolicyFile q = FrequencyPolicyFromText(CanonicalPolicyText(p), "canonical");
  EXPECT_TRUE(q.net.actor().params() == p.net.actor().params()) << "bitwise";
  EXPECT_TRUE(q.net.critic().params() == p.net.critic().params());
  EXPECT_EQ(q.net.critic().params()[7], 5e-324);
  EXPECT_EQ(CanonicalPolicyText(q), CanonicalPolicyText(p));
}

TEST(PolicyIoTest, WeightThatFloat32CannotHoldIsNotWritten) {
  PolicyFile p = SamplePolicy();
  p.net.critic().params()[3] = 1e300;  // W_0 is stored column-major: row 3, column 0
  const std::string path = TempPath("policy_overflow.json");
  WriteText(path, "kept");
  try {
    SavePolicyFile(path, p);
    ADD_FAILURE() << "saved";
  } catch (const std::domain_error& e) {
    EXPECT_NE(std::string(e.what()).find("critic.layers[0].weights[3][0] is beyond float32's range"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadText(path), "kept") << "the existing file is untouched";
  p.net.critic().params()[3] = std::nan("");
  EXPECT_THROW(PolicyToJson(p, WeightPrecision::kFloat64), std::domain_error);
  std::remove(path.c_str());
}

// The version 1 layout (weights as nested decimal arrays): files written before version 2.
json Version1(const PolicyFile& p) {
  json j = PolicyToJson(p, WeightPrecision::kFloat64);
  j["version"] = 1;
  j.erase("parameters");
  for (const auto& [name, mlp] : {std::pair{"actor", &p.net.actor()}, std::pair{"critic", &p.net.critic()}}) {
    json layers = json::array();
    for (int l = 0; l < mlp->num_layers(); ++l) {
      const auto W = mlp->W(l);
      json rows = json::array();
      for (Eigen::Index i = 0; i < W.rows(); ++i) {
        rows.push_back(std::vector<double>(W.row(i).begin(), W.row(i).end()));
      }
      layers.push_back({{"in", W.cols()},
                        {"out", W.rows()},
                        {"weights", rows},
                        {"bias", std::vector<double>(mlp->b(l).begin(), mlp->b(l).end())}});
    }
    j[name] = {{"layers", layers}};
  }
  return j;
}

TEST(PolicyIoTest, Version1FileStillLoadsBitExactly) {
  const PolicyFile p = SamplePolicy();
  const std::string path = TempPath("policy_v1.json");
  WriteText(path, Version1(p).dump(1));
  const PolicyFile q = LoadFrequencyPolicy(path);
  EXPECT_TRUE(q.net.actor().params() == p.net.actor().params()) << "bitwise";
  EXPECT_TRUE(q.net.critic().params() == p.net.critic().params());
  std::remove(path.c_str());
}

// Writes `document` (by default SamplePolicy as saved) with `damage` applied, and expects
// LoadFrequencyPolicy to throw std::invalid_argument whose message names the file and contains
// `field`.
void ExpectRefused(const std::string& name, const std::function<void(json&)>& damage,
                   const std::string& field,
                   const json& document = PolicyToJson(SamplePolicy(), WeightPrecision::kFloat32)) {
  const std::string path = TempPath("policy_" + name + ".json");
  json j = document;
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
  std::string text = PolicyToJson(SamplePolicy(), WeightPrecision::kFloat32).dump();
  const std::size_t pos = text.find("\"mean\":[") + 8;
  WriteText(path, text.substr(0, pos) + "NaN" + text.substr(text.find_first_of(",]", pos)));
  EXPECT_THROW(LoadFrequencyPolicy(path), std::invalid_argument);
  WriteText(path, text.substr(0, pos) + "1e999" + text.substr(text.find_first_of(",]", pos)));
  EXPECT_THROW(LoadFrequencyPolicy(path), std::invalid_argument);
  std::remove(path.c_str());
}

TEST(PolicyIoTest, WrongFormatOrUnknownVersionIsRefused) {
  ExpectRefused("format", [](json& j) { j["format"] = "something-else"; }, "format");
  ExpectRefused("version", [](json& j) { j["version"] = 3; }, "version");
  ExpectRefused("version_type", [](json& j) { j["version"] = "1"; }, "version");
  ExpectRefused("not_object", [](json& j) { j = json::array(); }, "(root)");
}

// Re-encodes a damaged weight block with a matching sha256, so the check after it is reached.
void SetWeightBytes(json& j, const std::string& bytes) {
  j["parameters"]["data"] = api::Base64Encode(bytes);
  j["parameters"]["sha256"] = api::Sha256Hex(bytes);
}

std::string WeightBytes(const json& j) { return api::Base64Decode(j["parameters"]["data"].get<std::string>()); }

TEST(PolicyIoTest, DamagedWeightBlockIsNamed) {
  ExpectRefused("no_parameters", [](json& j) { j.erase("parameters"); }, "parameters");
  ExpectRefused("dtype", [](json& j) { j["parameters"]["dtype"] = "float16"; }, "parameters.dtype");
  ExpectRefused("byte_order", [](json& j) { j["parameters"]["byte_order"] = "big"; }, "parameters.byte_order");
  ExpectRefused("layout", [](json& j) { j["parameters"]["layout"] = "critic then actor"; }, "parameters.layout");
  ExpectRefused("count", [](json& j) { j["parameters"]["count"] = 12; }, "parameters.count");
  ExpectRefused("bad_sha", [](json& j) { j["parameters"]["sha256"] = std::string(64, '0'); }, "parameters.sha256");
  // One flipped bit in the weights: the digest no longer matches.
  ExpectRefused("bit_flip",
                [](json& j) {
                  std::string bytes = WeightBytes(j);
                  bytes[1000] ^= 4;
                  j["parameters"]["data"] = api::Base64Encode(bytes);
                },
                "parameters.sha256");
  ExpectRefused("truncated",
                [](json& j) { SetWeightBytes(j, WeightBytes(j).substr(0, 4000)); },
                "parameters.data: truncated: 4000 bytes");
  ExpectRefused("too_long", [](json& j) { SetWeightBytes(j, WeightBytes(j) + "abcd"); }, "parameters.data: too long");
  ExpectRefused("not_base64", [](json& j) { j["parameters"]["data"] = "AAA*"; }, "parameters.data");
  ExpectRefused("base64_cut",
                [](json& j) {
                  const std::string text = j["parameters"]["data"];
                  j["parameters"]["data"] = text.substr(0, text.size() - 3);
                },
                "parameters.data");
  ExpectRefused("float64_as_float32", [](json& j) { j["parameters"]["dtype"] = "float64"; }, "parameters.data");
}

TEST(PolicyIoTest, NonFiniteWeightIsNamed) {
  // NaN in the first critic layer's weight [0][2], with a matching digest.
  const auto actor = MakeFrequencyPolicy(ActionGrid(), 1).net.actor().num_params();
  ExpectRefused("nan_weight",
                [actor](json& j) {
                  std::string bytes = WeightBytes(j);
                  const float nan = std::numeric_limits<float>::quiet_NaN();
                  std::memcpy(&bytes[4 * (actor + 2)], &nan, 4);
                  SetWeightBytes(j, bytes);
                },
                "parameters.data: critic.layers[0].weights[0][2] is not finite");
}

TEST(PolicyIoTest, MissingFieldsAreNamed) {
  ExpectRefused("no_critic", [](json& j) { j.erase("critic"); }, "critic", Version1(SamplePolicy()));
  ExpectRefused("no_bias", [](json& j) { j["actor"]["layers"][1].erase("bias"); },
                "actor.layers[1].bias", Version1(SamplePolicy()));
  ExpectRefused("no_normaliser", [](json& j) { j["observation"].erase("normaliser"); },
                "observation.normaliser");
}

TEST(PolicyIoTest, WrongShapesAreNamed) {
  const json v1 = Version1(SamplePolicy());
  ExpectRefused("row_missing", [](json& j) { j["actor"]["layers"][0]["weights"].erase(3); },
                "actor.layers[0].weights", v1);
  ExpectRefused("row_short", [](json& j) { j["critic"]["layers"][1]["weights"][7].erase(0); },
                "critic.layers[1].weights[7]", v1);
  ExpectRefused("bias_long", [](json& j) { j["actor"]["layers"][2]["bias"].push_back(0.0); },
                "actor.layers[2].bias", v1);
  ExpectRefused("layer_missing", [](json& j) { j["critic"]["layers"].erase(2); }, "critic.layers", v1);
  ExpectRefused("hidden_changed_v1", [](json& j) { j["architecture"]["hidden"][1] = 149; },
                "actor.layers[1].out", v1);
  ExpectRefused("hidden_changed", [](json& j) { j["architecture"]["hidden"][1] = 149; }, "parameters.count");
  ExpectRefused("grid_short", [](json& j) { j["action_grid"]["actions"].erase(0); },
                "action_grid.actions");
  ExpectRefused("mean_short", [](json& j) { j["observation"]["normaliser"]["mean"].erase(0); },
                "observation.normaliser.mean");
  ExpectRefused("huge", [](json& j) { j["architecture"]["hidden"] = {60000, 60000}; },
                "architecture");
}

TEST(PolicyIoTest, NonFiniteOrNonNumericValuesAreNamed) {
  // NaN and inf are written as null by JSON serialisers; strings are plain corruption.
  const json v1 = Version1(SamplePolicy());
  ExpectRefused("null_weight", [](json& j) { j["actor"]["layers"][1]["weights"][2][5] = nullptr; },
                "actor.layers[1].weights[2][5]", v1);
  ExpectRefused("string_bias", [](json& j) { j["critic"]["layers"][0]["bias"][0] = "NaN"; },
                "critic.layers[0].bias[0]", v1);
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

// The factored head (one output per level of f_per, f_col, f_dif) is rebuilt from the grid on load.
TEST(PolicyIoTest, FactoredHeadRoundTripsAndIsRebuiltFromTheGrid) {
  PolicyFile p = MakeFrequencyPolicy(ActionGrid(), 31, PolicyHead::kFactored);
  ASSERT_TRUE(p.net.config().factored());
  EXPECT_EQ(p.net.actor().output_size(), 4 + 5 + 7) << "the default grid's levels";
  Rng rng(3);
  p.net.actor().InitOrthogonal(&rng, 3.0);  // spread logits, so the greedy choice means something
  const json doc = PolicyToJson(p, WeightPrecision::kFloat64);
  EXPECT_EQ(doc["architecture"]["actor_output"], "factored_masked_categorical_logits");
  const PolicyFile q = FrequencyPolicyFromText(doc.dump(), "factored");
  EXPECT_EQ(q.net.config().action_terms, p.net.config().action_terms);
  EXPECT_TRUE(q.net.actor().params() == p.net.actor().params());
  ActorCritic::Workspace wp = p.net.MakeWorkspace(), wq = q.net.MakeWorkspace();
  const std::vector<std::uint8_t> all(98, 1);
  for (int k = 0; k < 20; ++k) {
    Eigen::VectorXd obs(kPolicyStateDim);
    for (int i = 0; i < kPolicyStateDim; ++i) obs[i] = rng.Normal();
    const PolicyOutput a = p.net.Act(obs, all, ActMode::kGreedy, nullptr, &wp);
    const PolicyOutput b = q.net.Act(obs, all, ActMode::kGreedy, nullptr, &wq);
    EXPECT_EQ(a.action, b.action);
    EXPECT_EQ(a.log_prob, b.log_prob);
  }
  ExpectRefused("factored_no_grid", [](json& j) { j["action_grid"] = nullptr; }, "architecture.actor_output", doc);
  ExpectRefused("head_unknown", [](json& j) { j["architecture"]["actor_output"] = "gaussian"; },
                "architecture.actor_output");
  ExpectRefused("head_missing", [](json& j) { j["architecture"].erase("actor_output"); },
                "architecture.actor_output");
  // A joint file's weights under a factored header no longer fit.
  ExpectRefused("head_swapped", [](json& j) { j["architecture"]["actor_output"] = "factored_masked_categorical_logits"; },
                "parameters.count");
}

TEST(PolicyIoTest, GenericPolicyWithoutGridRoundTrips) {
  PolicyFile p{ActorCritic({3, 5, {4}}), {"a", "b", "c"}, std::nullopt, json::object()};
  Rng rng(1);
  p.net.InitializeWeights(&rng);
  const PolicyFile q = PolicyFromJson(PolicyToJson(p, WeightPrecision::kFloat64), "test");
  EXPECT_FALSE(q.action_grid.has_value());
  EXPECT_TRUE(q.net.actor().params() == p.net.actor().params());
  EXPECT_EQ(q.feature_names, p.feature_names);
}

}  // namespace
}  // namespace enavi::navstack::rl
