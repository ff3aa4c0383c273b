// SPDX-License-Identifier: BSD-3-Clause
// Scene: binding the channels' voxels (setVolume, dataModified).
#include "mcvol/Scene.h"

#include "SceneInternal.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mcvol
{
using detail::channelText;

void Scene::setVolume(const int dims[3], int numChannels, const ChannelSource* channels)
{
  for (int a = 0; a < 3; ++a)
  {
    if (dims[a] < 1)
    {
      throw std::invalid_argument("mcvol: the volume has an empty extent (dimension " + std::to_string(a) + " is " +
        std::to_string(dims[a]) + ")");
    }
  }
  if (numChannels < 1 || numChannels > kMaxChannels)
  {
    throw std::invalid_argument("mcvol: " + std::to_string(numChannels) + " channels given; 1 to " +
      std::to_string(kMaxChannels) + " are supported");
  }
  for (int n = 0; n < numChannels; ++n)
  {
    if (!channels[n].data)
    {
      throw std::invalid_argument("mcvol: " + channelText(n) + " has no data");
    }
    if (channels[n].stride < 1)
    {
      throw std::invalid_argument("mcvol: " + channelText(n) + " has a stride below 1");
    }
    if (!std::isfinite(channels[n].offset) || (channels[n].offset != 0.0 && channels[n].type != ScalarType::Float64))
    {
      throw std::invalid_argument("mcvol: " + channelText(n) +
        " has an offset; only finite offsets of float64 channels "
        "are supported");
    }
    if (channels[n].format != ChannelFormat::Scalar && channels[n].format != ChannelFormat::Extinction)
    {
      throw std::invalid_argument(
        "mcvol: " + channelText(n) + " has an unknown channel format (" + std::to_string(int(channels[n].format)) + ")");
    }
    if (channels[n].format == ChannelFormat::Extinction)
    {
      if (channels[n].type != ScalarType::Float32 && channels[n].type != ScalarType::Float16)
      {
        throw std::invalid_argument("mcvol: " + channelText(n) +
          " is pre-classified (extinction format) and must be float32 or float16 (sigma, sigma r, sigma g, sigma b), "
          "not " +
          toString(channels[n].type));
      }
      if (channels[n].stride < 4)
      {
        throw std::invalid_argument("mcvol: " + channelText(n) +
          " is pre-classified (extinction format): its stride must be at least 4 values (4 per voxel), not " +
          std::to_string(channels[n].stride));
      }
    }
    else if (channels[n].type == ScalarType::Float16)
    {
      throw std::invalid_argument("mcvol: " + channelText(n) +
        " is float16; only pre-classified (extinction format) channels may be float16");
    }
    const bool scaled = channels[n].format == ChannelFormat::Extinction && channels[n].type == ScalarType::Float16;
    if (!(std::isfinite(channels[n].scale) && channels[n].scale > 0.0) || (!scaled && channels[n].scale != 1.0))
    {
      throw std::invalid_argument("mcvol: " + channelText(n) + " has a scale of " +
        std::to_string(channels[n].scale) +
        "; only float16 pre-classified channels are scaled, by a finite factor above 0");
    }
    // visitScalarType() reads a value outside the enum as float32, which
    // could read past the end of a narrower array; reject it here, once.
    if (int(channels[n].type) < int(ScalarType::UInt8) || int(channels[n].type) > int(ScalarType::Float16))
    {
      throw std::invalid_argument(
        "mcvol: " + channelText(n) + " has an unknown scalar type (" + std::to_string(int(channels[n].type)) + ")");
    }
  }
  const bool sameShape = numChannels == this->NumChannels && dims[0] == this->Dims[0] && dims[1] == this->Dims[1] &&
    dims[2] == this->Dims[2];
  std::copy(dims, dims + 3, this->Dims);
  if (!sameShape)
  {
    this->HasTF.fill(false);
  }
  for (int n = 0; n < numChannels; ++n)
  {
    if (channels[n].offset != this->Channels[size_t(n)].offset)
    {
      this->HasTF[size_t(n)] = false; // its table was placed relative to the old offset
    }
  }
  this->NumChannels = numChannels;
  std::copy(channels, channels + numChannels, this->Channels.begin());
  this->HasIndexBounds = false;
  this->MacrocellsDirty = true;
  ++this->ContentVersion;
}

void Scene::setIndexBounds(const double lo[3], const double hi[3])
{
  if (this->NumChannels == 0)
  {
    throw std::invalid_argument("mcvol: setIndexBounds needs a volume (setVolume) first");
  }
  for (int a = 0; a < 3; ++a)
  {
    const double first = this->Dims[a] == 1 ? -0.5 : 0.0;
    const double last = this->Dims[a] == 1 ? 0.5 : double(this->Dims[a] - 1);
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || !(lo[a] < hi[a]) || lo[a] < first - 0.5 ||
      hi[a] > last + 0.5)
    {
      throw std::invalid_argument("mcvol: the index bounds [" + std::to_string(lo[a]) + ", " + std::to_string(hi[a]) +
        "] of axis " + std::to_string(a) + " must be finite, not empty, and within half a voxel of the volume's [" +
        std::to_string(first) + ", " + std::to_string(last) + "]");
    }
  }
  this->HasIndexBounds = true;
  for (int a = 0; a < 3; ++a)
  {
    this->IndexBoundsLo[a] = lo[a];
    this->IndexBoundsHi[a] = hi[a];
    // The grids do not depend on the box: the view takes it at once.
    this->View.volume.boxLo[a] = float(lo[a]);
    this->View.volume.boxHi[a] = float(hi[a]);
  }
}

void Scene::dataModified()
{
  this->MacrocellsDirty = true;
  ++this->ContentVersion;
}
} // namespace mcvol
