// SPDX-License-Identifier: BSD-3-Clause
// Bad input to the Scene (and renderer) throws std::invalid_argument
// whose message names the problem; the Scene stays usable afterwards.
#include "TestUtil.h"

#include <functional>
#include <limits>
#include <stdexcept>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
template <typename E = std::invalid_argument>
void expectThrowNaming(const std::function<void()>& fn, const std::vector<std::string>& words, const std::string& what)
{
  try
  {
    fn();
    ADD_FAILURE() << what << ": no exception";
  }
  catch (const E& e)
  {
    const std::string msg = e.what();
    for (const std::string& w : words)
    {
      EXPECT_NE(msg.find(w), std::string::npos)
        << what << ": message \"" << msg << "\" does not mention \"" << w << "\"";
    }
  }
  catch (const std::exception& e)
  {
    ADD_FAILURE() << what << ": wrong exception type: " << e.what();
  }
}

struct Fixture
{
  TestVolume v{ 4, 5, 6, 2, 0.5f };
  std::vector<ChannelSource> src = v.sources();
};
} // namespace

TEST(SceneAPI, SetVolumeErrors)
{
  Fixture f;
  Scene s;
  for (int a = 0; a < 3; ++a)
  {
    int dims[3] = { 4, 5, 6 };
    dims[a] = 0;
    expectThrowNaming([&] { s.setVolume(dims, 2, f.src.data()); }, { "empty extent", "dimension " + std::to_string(a) },
      "zero dimension");
    dims[a] = -3;
    expectThrowNaming(
      [&] { s.setVolume(dims, 2, f.src.data()); }, { "dimension " + std::to_string(a), "-3" }, "negative dimension");
  }
  std::vector<ChannelSource> many(40, f.src[0]);
  expectThrowNaming([&] { s.setVolume(f.v.dims, 0, f.src.data()); }, { "0 channels", "1 to 32" }, "0 channels");
  expectThrowNaming([&] { s.setVolume(f.v.dims, 33, many.data()); }, { "33 channels", "1 to 32" }, "33 channels");
  std::vector<ChannelSource> bad = f.src;
  bad[1].data = nullptr;
  expectThrowNaming([&] { s.setVolume(f.v.dims, 2, bad.data()); }, { "channel 1", "no data" }, "null data");
  bad = f.src;
  bad[0].stride = 0;
  expectThrowNaming([&] { s.setVolume(f.v.dims, 2, bad.data()); }, { "channel 0", "stride" }, "zero stride");
  expectThrowNaming([&] { s.setMacrocellSize(0); }, { "macrocell size" }, "macrocell size 0");
  // 32 channels is the limit and works.
  EXPECT_NO_THROW(s.setVolume(f.v.dims, 32, many.data()));
}

TEST(SceneAPI, TransferFunctionErrors)
{
  Fixture f;
  Scene s;
  s.setVolume(f.v.dims, 2, f.src.data());
  const TransferFunctionDesc good = flatTF(0.5f, 1, 0, 0, 1.f, 4);

  TransferFunctionDesc tf = good;
  tf.rgb.pop_back();
  expectThrowNaming(
    [&] { s.setTransferFunction(0, tf); }, { "channel 0", "3 colour values per entry" }, "rgb size not 3K");
  tf = good;
  tf.opacity.resize(1);
  tf.rgb.resize(3);
  expectThrowNaming([&] { s.setTransferFunction(1, tf); }, { "channel 1", "at least 2 opacity entries" }, "K = 1");
  tf = good;
  tf.opacity[2] = std::numeric_limits<float>::quiet_NaN();
  expectThrowNaming([&] { s.setTransferFunction(0, tf); }, { "channel 0", "non-finite" }, "NaN opacity");
  tf = good;
  tf.rgb[4] = std::numeric_limits<float>::infinity();
  expectThrowNaming([&] { s.setTransferFunction(0, tf); }, { "non-finite" }, "Inf colour");
  for (float u : { 0.f, -1.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity() })
  {
    tf = good;
    tf.unitDistance = u;
    expectThrowNaming(
      [&] { s.setTransferFunction(1, tf); }, { "channel 1", "unit distance" }, "unit distance " + std::to_string(u));
  }
  tf = good;
  tf.scalarMin = 2.f;
  tf.scalarMax = 1.f;
  expectThrowNaming([&] { s.setTransferFunction(0, tf); }, { "scalar range" }, "inverted range");
  tf.scalarMin = std::numeric_limits<float>::quiet_NaN();
  expectThrowNaming([&] { s.setTransferFunction(0, tf); }, { "scalar range" }, "NaN range");
  expectThrowNaming([&] { s.setTransferFunction(2, good); }, { "channel 2", "2 channels" }, "channel out of range");
  expectThrowNaming([&] { s.setTransferFunction(-1, good); }, { "channel -1" }, "negative channel");
  // Tables of different sizes across channels.
  s.setTransferFunction(0, good);
  expectThrowNaming([&] { s.setTransferFunction(1, flatTF(0.5f, 1, 0, 0, 1.f, 8)); }, { "same size", "channel 1", "8" },
    "mismatched table sizes");
  const float neg[2] = { 1.f, -1.f };
  expectThrowNaming([&] { s.setMixWeights(neg, 2); }, { "mix weight 1" }, "negative mix weight");
}

TEST(SceneAPI, UpdateErrors)
{
  Scene empty;
  expectThrowNaming([&] { empty.update(); }, { "no volume" }, "update without a volume");
  Fixture f;
  Scene s;
  s.setVolume(f.v.dims, 2, f.src.data());
  s.setTransferFunction(0, flatTF(0.5f, 1, 0, 0));
  expectThrowNaming([&] { s.update(); }, { "channel 1", "no transfer function" }, "channel lacking a TF");
  // Fixing the input makes the Scene usable.
  s.setTransferFunction(1, flatTF(0.5f, 0, 1, 0));
  EXPECT_NO_THROW(s.update());
  EXPECT_EQ(s.view().numActive, 2);
  // A new volume of another shape drops the old transfer functions.
  int dims[3] = { 3, 3, 3 };
  s.setVolume(dims, 2, f.src.data());
  expectThrowNaming([&] { s.update(); }, { "channel 0", "no transfer function" }, "TFs after reshaping");
}

TEST(SceneAPI, RendererErrors)
{
  Fixture f;
  CPURenderer r;
  Accumulator acc;
  Camera cam;
  cam.width = 4;
  cam.height = 4;
  Scene notReady;
  EXPECT_THROW(r.render(notReady, cam, RenderSettings(), nullptr, acc), std::logic_error);
  Scene s;
  configure(s, f.v, { flatTF(0.5f, 1, 0, 0), flatTF(0.5f, 0, 1, 0) });
  RenderSettings rs;
  rs.samplesPerPixel = 0;
  expectThrowNaming([&] { r.render(s, cam, rs, nullptr, acc); }, { "samples per pixel" }, "0 spp");
  cam.width = 0;
  expectThrowNaming([&] { r.render(s, cam, RenderSettings(), nullptr, acc); }, { "image size" }, "empty image");
  expectThrowNaming([&] { acc.resize(-1, 2); }, { "negative image size" }, "negative accumulator");
}
