// SPDX-License-Identifier: BSD-3-Clause
// Scene: sampling a channel's transfer function into its table of
// (r, g, b, extinction) texels.
#include "mcvol/Scene.h"

#include "SceneInternal.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mcvol
{
using detail::channelText;

float opacityToExtinction(float opacity, float unitDistance)
{
  const float a = std::min(std::max(opacity, 0.f), kMaxOpacity);
  return float(-std::log1p(-double(a)) / double(unitDistance));
}

void Scene::setTransferFunction(int channel, const TransferFunctionDesc& tf)
{
  if (channel < 0 || channel >= this->NumChannels)
  {
    throw std::invalid_argument("mcvol: transfer function for " + channelText(channel) + ", but the volume has " +
      std::to_string(this->NumChannels) + " channels");
  }
  const size_t K = tf.opacity.size();
  if (K < 2 || tf.rgb.size() != 3 * K)
  {
    throw std::invalid_argument("mcvol: the transfer function of " + channelText(channel) +
      " needs at least 2 opacity entries and 3 colour values per entry");
  }
  if (!(tf.unitDistance > 0.f) || !std::isfinite(tf.unitDistance))
  {
    throw std::invalid_argument(
      "mcvol: the opacity unit distance of " + channelText(channel) + " must be a positive finite number");
  }
  if (!std::isfinite(tf.scalarMin) || !std::isfinite(tf.scalarMax) || !(tf.scalarMax >= tf.scalarMin) ||
    std::fabs(tf.scalarMin) > 3e38 || std::fabs(tf.scalarMax) > 3e38)
  {
    throw std::invalid_argument(
      "mcvol: the scalar range of " + channelText(channel) + "'s transfer function is invalid");
  }
  for (size_t i = 0; i < K; ++i)
  {
    if (!std::isfinite(tf.opacity[i]) || !std::isfinite(tf.rgb[3 * i]) || !std::isfinite(tf.rgb[3 * i + 1]) ||
      !std::isfinite(tf.rgb[3 * i + 2]))
    {
      throw std::invalid_argument(
        "mcvol: the transfer function of " + channelText(channel) + " has a non-finite entry");
    }
  }
  const int Kcur = this->View.tables.size;
  if (int(K) != Kcur)
  {
    for (int n = 0; n < this->NumChannels; ++n)
    {
      if (n != channel && this->HasTF[n])
      {
        throw std::invalid_argument("mcvol: all channels' transfer-function tables must have the same size (" +
          std::to_string(Kcur) + " entries, " + channelText(channel) + " has " + std::to_string(K) + ")");
      }
    }
    this->Tables.assign(size_t(kMaxChannels) * K * 4, 0.f);
    this->View.tables.size = int(K);
  }
  float* t = this->Tables.data() + size_t(channel) * K * 4;
  for (size_t i = 0; i < K; ++i)
  {
    t[4 * i + 0] = std::min(std::max(tf.rgb[3 * i + 0], 0.f), 1.f);
    t[4 * i + 1] = std::min(std::max(tf.rgb[3 * i + 1], 0.f), 1.f);
    t[4 * i + 2] = std::min(std::max(tf.rgb[3 * i + 2], 0.f), 1.f);
    t[4 * i + 3] = opacityToExtinction(tf.opacity[i], tf.unitDistance);
  }
  // The table's range in the units the per-ray code sees (offset taken off),
  // with a width that keeps (K - 1) / width a finite float: a constant
  // channel, or one whose range is narrower than float resolution, would
  // otherwise get an infinite scale and NaN texel coordinates.
  const double lo = tf.scalarMin - this->Channels[size_t(channel)].offset;
  double width = tf.scalarMax - tf.scalarMin;
  const double minWidth = std::max(1e-30, 1e-6 * std::fabs(lo));
  if (!(width >= minWidth))
  {
    width = minWidth;
  }
  this->View.tables.scalarMin[channel] = float(lo);
  this->View.tables.scale[channel] = float(double(K - 1) / width);
  this->HasTF[channel] = true;
  this->MajorantDirty[channel] = true;
  ++this->ChannelTableVersion[size_t(channel)];
  ++this->TableVersion;
}
} // namespace mcvol
