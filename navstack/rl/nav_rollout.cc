#include "navstack/rl/nav_rollout.h"

#include <cmath>
#include <stdexcept>

#include <zlib.h>

#include "navstack/rl/blob_io.h"
#include "navstack/rl/rollout.h"

namespace enavi::navstack::rl {
namespace {

using detail::BlobReader;
using detail::Put;

constexpr char kMagic[4] = {'E', 'N', 'V', '1'};
constexpr std::uint32_t kMaxSide = 640;  // the sensor's width: no observation is larger
// The steps of one episode, uncompressed: bounded so that a corrupt header cannot ask for more.
constexpr std::size_t kMaxStepBytes = std::size_t{1} << 30;

std::size_t StepBytes(std::size_t pixels) { return pixels * 2 + (kNavStateSize + kNavActionSize + 2) * 8 + 1; }

}  // namespace

double NavRollout::Return() const {
  double r = 0;
  for (const NavRolloutStep& s : steps) r += s.reward;
  return r;
}

std::vector<std::uint16_t> QuantizeDepth(const std::vector<float>& depth) {
  std::vector<std::uint16_t> out(depth.size());
  for (std::size_t i = 0; i < depth.size(); ++i)
    out[i] = static_cast<std::uint16_t>(std::lround(std::clamp(double(depth[i]), 0.0, 1.0) * 65535.0));
  return out;
}

float DepthValue(std::uint16_t stored) { return static_cast<float>(stored / 65535.0); }

bool IsNavRolloutBlob(std::string_view bytes) {
  return bytes.size() >= 4 && bytes.substr(0, 4) == std::string_view(kMagic, 4);
}

std::string EncodeNavRollout(const NavRollout& rollout) {
  const std::size_t pixels = static_cast<std::size_t>(rollout.width) * static_cast<std::size_t>(rollout.height);
  std::string body;
  body.reserve(rollout.steps.size() * StepBytes(pixels));
  for (const NavRolloutStep& s : rollout.steps) {
    if (s.depth.size() != pixels) throw std::logic_error("EncodeNavRollout: a step's depth is not width x height");
    body.append(reinterpret_cast<const char*>(s.depth.data()), pixels * sizeof(std::uint16_t));
    for (int i = 0; i < kNavStateSize; ++i) Put(&body, s.state[i]);
    for (int i = 0; i < kNavActionSize; ++i) Put(&body, s.action[i]);
    Put(&body, s.log_prob);
    Put(&body, s.reward);
    Put(&body, static_cast<std::uint8_t>(s.done ? 1 : 0));
  }
  std::string out(kMagic, 4);
  Put(&out, static_cast<std::uint32_t>(rollout.width));
  Put(&out, static_cast<std::uint32_t>(rollout.height));
  Put(&out, static_cast<std::uint32_t>(rollout.steps.size()));
  Put(&out, rollout.max_depth_m);
  detail::PutIdAndInfo(&out, rollout.id, rollout.info);
  uLongf packed = compressBound(static_cast<uLong>(body.size()));
  const std::size_t head = out.size();
  out.resize(head + packed);
  // Level 1: most of level 9's ratio on depth images at a fraction of the time.
  if (compress2(reinterpret_cast<Bytef*>(out.data() + head), &packed, reinterpret_cast<const Bytef*>(body.data()),
                static_cast<uLong>(body.size()), 1) != Z_OK)
    throw std::runtime_error("EncodeNavRollout: zlib could not compress the steps");
  out.resize(head + packed);
  return out;
}

NavRollout DecodeNavRollout(std::string_view bytes, const std::string& source) {
  BlobReader r(bytes, source);
  if (r.Bytes(4, "magic") != std::string_view(kMagic, 4)) r.Fail("magic", "not an ENV1 nav rollout");
  NavRollout out;
  const auto width = r.Get<std::uint32_t>("width");
  const auto height = r.Get<std::uint32_t>("height");
  const auto steps = r.Get<std::uint32_t>("steps");
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    r.Fail("width", std::to_string(width) + "x" + std::to_string(height) + " is not an image size of the sensor");
  out.width = static_cast<int>(width);
  out.height = static_cast<int>(height);
  out.max_depth_m = r.Finite("max_depth_m");
  if (!(out.max_depth_m > 0)) r.Fail("max_depth_m", "must be > 0");
  detail::ReadIdAndInfo(&r, &out.id, &out.info);
  const std::size_t pixels = std::size_t{width} * height;
  const std::size_t need = std::size_t{steps} * StepBytes(pixels);
  if (need > kMaxStepBytes) r.Fail("steps", std::to_string(steps) + " steps of " + std::to_string(pixels) +
                                                " pixels exceed the 1 GiB bound of one rollout");
  const std::string_view packed = r.Bytes(r.left(), "steps");
  std::string body(need, '\0');
  uLongf got = static_cast<uLongf>(need);
  const int z = uncompress(reinterpret_cast<Bytef*>(body.data()), &got, reinterpret_cast<const Bytef*>(packed.data()),
                           static_cast<uLong>(packed.size()));
  if (z != Z_OK || got != need)
    r.Fail("steps", "the compressed steps do not decode to " + std::to_string(steps) + " steps (" +
                        (z == Z_OK ? std::to_string(got) + " bytes" : std::string("zlib: ") + zError(z)) + ")");
  BlobReader b(body, source);
  out.steps.resize(steps);
  for (std::uint32_t t = 0; t < steps; ++t) {
    NavRolloutStep& s = out.steps[t];
    s.depth.resize(pixels);
    std::memcpy(s.depth.data(), b.Bytes(pixels * 2, "depth").data(), pixels * 2);
    for (int i = 0; i < kNavStateSize; ++i) s.state[i] = b.Finite("state");
    for (int i = 0; i < kNavActionSize; ++i) s.action[i] = b.Finite("action");
    s.log_prob = b.Finite("log_prob");
    s.reward = b.Finite("reward");
    const auto done = b.Get<std::uint8_t>("done");
    if (done > 1) b.Fail("steps[" + std::to_string(t) + "].done", "must be 0 or 1");
    if (done == 1 && t + 1 != steps) b.Fail("steps[" + std::to_string(t) + "].done", "a terminal before the last step");
    s.done = done == 1;
  }
  return out;
}

std::size_t CheckRolloutBlob(std::string_view bytes, const std::string& source) {
  return IsNavRolloutBlob(bytes) ? DecodeNavRollout(bytes, source).steps.size()
                                 : DecodeRollout(bytes, source).steps.size();
}

}  // namespace enavi::navstack::rl
