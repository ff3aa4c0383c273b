// SPDX-License-Identifier: BSD-3-Clause
//
// One render on the GPU: the per-render scene view, the device accumulation
// image and depth buffer, the render kernel launch, the work counters and the
// read-back; and a round of estimator pilots launched at once
// (renderPilots()). The kernels are launchers: the per-pixel work is
// renderPixel<Mode>() from the core (Integrator.h -> Tracking.h -> DDA.h,
// Sampling.h), the same functions the OpenMP backend runs, compiled for the
// device through MCVOL_HOST_DEVICE.
#include "CUDARenderKernels.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace mcvol
{
namespace
{
/**
 * The visibility optimization's kernel (Lerzer and Dachsbacher, the
 * importance segments of their Algorithm 1): as renderKernel, with the
 * pixel's importance segment list refined first on the refining renders
 * (refinePass >= 0) and passed to the tracking. A kernel of its own, so that
 * the other kernels carry none of the importance code and its registers.
 */
template <BlendMode Mode, bool Lit>
__global__ void renderOptimizedKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ FrameParams fp, const float* __restrict__ depth, float4* __restrict__ accum,
  double* __restrict__ sums, float4* __restrict__ even, double* __restrict__ evenSums, uint32_t previous,
  unsigned long long* __restrict__ counters, ImportanceSegment* __restrict__ segments, uint8_t* __restrict__ counts, float* __restrict__ totals, int refinePass)
{
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);
  RayCounters c;
  unsigned long long overflow = 0;
  if (x < cam.width && y < cam.height)
  {
    const size_t p = size_t(y) * size_t(cam.width) + size_t(x);
    const float z = depth ? depth[p] : 1.f;
    ImportanceSegment* seg = segments + p * size_t(kImportanceCapacity);
    int count = counts[p];
    float total = totals[p];
    if (refinePass >= 0)
    {
      bool full = false;
      count = refineImportance(s, cam, x, y, z, refinePass, fp.seed, seg, count, total, full, c);
      counts[p] = uint8_t(count);
      totals[p] = total;
      overflow = full ? 1ull : 0ull;
    }
    RayImportance ri;
    ri.segments = seg;
    ri.count = count;
    ri.total = total;
    // The general kernels' light view: lightView() reads through a pointer.
    renderIntoPixel<Mode, Lit, true, 0>(
      s, lightView(s), cam, fp, x, y, z, p, c, &ri, accum, sums, even, evenSums, previous);
  }
  // Always counted (one atomic per warp and counter): the overflow count is
  // needed whatever the caller asked for.
  const unsigned long long dda = warpSumU64(c.ddaSteps);
  const unsigned long long tent = warpSumU64(c.tentative);
  const unsigned long long real = warpSumU64(c.real);
  const unsigned long long smp = warpSumU64(c.samples);
  const unsigned long long sca = Lit ? warpSumU64(c.scattering) : 0ull;
  const unsigned long long shd = Lit ? warpSumU64(c.shadowRays) : 0ull;
  const unsigned long long grd = Lit ? warpSumU64(c.gradients) : 0ull;
  const unsigned long long imp = warpSumU64(c.importance);
  const unsigned long long ovf = warpSumU64(overflow + c.importanceOverflows);
  const unsigned lane = (threadIdx.y * blockDim.x + threadIdx.x) & 31u;
  if (lane == 0)
  {
    atomicAdd(counters + 0, dda);
    atomicAdd(counters + 1, tent);
    atomicAdd(counters + 2, real);
    atomicAdd(counters + 3, smp);
    atomicAdd(counters + 4, sca);
    atomicAdd(counters + 5, shd);
    atomicAdd(counters + 6, grd);
    atomicAdd(counters + 7, imp);
    atomicAdd(counters + 8, ovf);
  }
}

/// Launches the visibility optimization's kernel for the blend mode and
/// lighting known at run time. Post-render composite is never lit here
/// (refused before the launch), so its lit kernel is not compiled.
void launchOptimized(BlendMode mode, bool lit, const SceneView& s, const CameraView& cam, const FrameParams& fp,
  const RenderLaunch& k, const ImportanceLaunch& o)
{
  withBlendMode(mode,
    [&](auto m)
    {
      withFlag(lit,
        [&](auto l)
        {
          constexpr BlendMode Mode = decltype(m)::value;
          if constexpr (decltype(l)::value && Mode == BlendMode::Composite)
          {
            throw std::logic_error("mcvol: lit post-render composite reached the CUDA launcher");
          }
          else
          {
            renderOptimizedKernel<Mode, decltype(l)::value><<<k.grid, k.block, 0, k.stream>>>(s, cam, fp, k.depth,
              k.accum, k.sums, k.even, k.evenSums, k.previous, k.counters, o.segments, o.counts, o.totals,
              o.refinePass);
          }
        });
    });
}

/// Launches the render kernel of a render or a pilot: the lit or unlit one
/// of the estimator's code (unlitEstimator()). The unlit kernels contain
/// none of the lighting code and the collision kernels none of the
/// expected-value estimator's, which saves registers; for plain scenes
/// (`plain`) the kernels come from CUDALaunchPlain.cu, compiled without the
/// pre-classified and cubic sampling.
void launchRender(BlendMode mode, bool count, bool lit, bool plain, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const RenderLaunch& k)
{
  const int unlit =
    unlitEstimator(fp.estimator, mode, lit, false, s.marchControlVariates, localKernels(s, mode, fp.estimator));
  if (plain)
  {
    launchPlain(mode, lit, unlit, count, s, cam, fp, k);
    return;
  }
  withBlendMode(mode, [&](auto m) { launchKernel<decltype(m)::value>(lit, unlit, count, s, cam, fp, k); });
}

/// Whether the plain kernels can sample `v`: scalar channels only, linear
/// or nearest interpolation.
bool plainChannels(const SceneView& v)
{
  bool plain = !v.volume.cubic;
  for (int n = 0; n < v.volume.numChannels; ++n)
  {
    plain = plain && v.volume.channels[n].format == ChannelFormat::Scalar;
  }
  return plain;
}

/// Whether the plain kernels can render `s`, whose light paths run in
/// `light` (RenderLaunch::light): plain channels in both, and no light path
/// that crosses a piece's boundary (kStandInCode, Lighting.h): no stand-in,
/// or an exact one.
bool plainScene(const SceneView& s, const SceneView& light)
{
  return plainChannels(s) && (!s.outside || (s.outsideExact && plainChannels(light)));
}

/// Adds the device's counters (`c`: DDA steps, tentative, real, channel
/// samples, scattering, shadow rays, gradients, importance samples) and
/// `rays` to `out`.
void addCounters(RenderCounters& out, const unsigned long long* c, uint64_t rays)
{
  out.rays += rays;
  out.ddaSteps += c[0];
  out.tentativeCollisions += c[1];
  out.realCollisions += c[2];
  out.channelSamples += c[3];
  out.scatteringEvents += c[4];
  out.shadowRays += c[5];
  out.gradientEvaluations += c[6];
  out.importanceSamples += c[7];
}

/// The per-render rates of the view: the extinction limit, the
/// expected-value and march rates, the march's variant.
void setRenderRates(SceneView& s, const RenderSettings& settings, const Camera& camera, const CameraView& cam)
{
  s.sigmaLimit = extinctionLimit(cam);
  s.minRate = settings.minSamplesPerVoxel > 0.f ? settings.minSamplesPerVoxel * voxelRate(cam) : 0.f;
  s.marchRate = settings.marchSamplesPerVoxel * voxelRate(cam);
  s.marchControlVariates = marchControlVariates(settings, camera);
}

/// The pilot streams: one per job of the largest round chooseEstimator()
/// makes (16 candidates), so that the jobs run side by side. Each job is one
/// launch of all its one-sample images (FrameParams::batchSamples), since
/// issuing a launch per image costs more host time than a small image takes
/// to render.
constexpr size_t kPilotStreams = 16;
/// The images a round's buffers hold at least: the largest round
/// chooseEstimator() makes at the default pilot size (expected value's
/// 2 x 8 images and 15 marches' 2 x 2).
constexpr size_t kReservedPilotImages = 96;

/// renderPilots()'s argument checks (render()'s for each job); returns the
/// one-sample images of the round (both replicates of every job).
size_t checkPilotJobs(const Camera& camera, std::vector<PilotJob>& jobs)
{
  size_t images = 0;
  for (PilotJob& job : jobs)
  {
    checkPilotCheckpoints(job);
    RenderSettings st = job.settings;
    st.samplesPerPixel = 1;
    Accumulator probe; // the argument checks of render()
    probe.setErrorEstimation(false);
    checkRenderArguments(camera, st, probe);
    images += 2 * size_t(job.checkpoints.back());
  }
  return images;
}

/// Each replicate's means at its checkpoints from the round's one-sample
/// images (`host`, in launch order) and its counters (`c`, a block of 9 per
/// job), summed as render() sums a pixel's samples (addSample(), storeSum()):
/// the same means as renders of the checkpoints' samples.
void foldPilotMeans(std::vector<PilotJob>& jobs, const float* host, const unsigned long long* c, size_t pixels)
{
  const size_t P = pixels;
  size_t image = 0;
  std::vector<Vec4d> sums(P);
  for (size_t j = 0; j < jobs.size(); ++j)
  {
    PilotJob& job = jobs[j];
    const int n = job.checkpoints.back();
    for (int r = 0; r < 2; ++r)
    {
      job.means[r].clear();
      std::vector<float> mean(4 * P, 0.f);
      std::fill(sums.begin(), sums.end(), Vec4d());
      int done = 0;
      for (int upTo : job.checkpoints)
      {
        // Each pixel's samples are added in their order, as pixel by pixel,
        // but each image is read once, in memory order.
        for (int k = done; k < upTo; ++k)
        {
          const float* v = host + 4 * (image + size_t(k)) * P;
          for (size_t p = 0; p < P; ++p)
          {
            addSample(sums[p], Vec4f{ v[4 * p], v[4 * p + 1], v[4 * p + 2], v[4 * p + 3] });
          }
        }
        for (size_t p = 0; p < P; ++p)
        {
          storeSum(mean.data() + 4 * p, nullptr, sums[p], uint32_t(upTo));
        }
        done = upTo;
        job.means[r].push_back(mean);
      }
      image += size_t(n);
    }
    job.counters = RenderCounters();
    addCounters(job.counters, c + 9 * j, uint64_t(P) * uint64_t(n));
  }
}
} // namespace

SceneView CUDARenderer::Internal::renderView(const Scene& scene, bool textures)
{
  // Per-render view: blend parameters, interpolation, sampling path and
  // lighting over the device copies that sync() keeps current.
  SceneView s = this->View;
  s.importance = ImportanceView(); // host pointers: never on the device
  const SceneView& hv = scene.view();
  s.blend = hv.blend;
  s.volume.nearest = hv.volume.nearest;
  s.volume.cubic = hv.volume.cubic;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    const DeviceChannel& dc = this->Channels[n];
    ChannelView& c = s.volume.channels[n];
    c.data = dc.bytes.ptr; // null for a texture-held channel
    c.format = dc.format;
    c.stride = dc.format == ChannelFormat::Extinction ? 4 : 1; // elements per voxel of `data`
    c.type = dc.type;
    c.offset = 0.0;
    // Texture-held channels (pre-classified ones as float4 texels):
    // hardware filtering when `textures`, else exact voxel reads through the
    // point object (the reference march). Cubic
    // sampling combines 8 linear fetches (Sigg and Hadwiger), so it takes the
    // linear object too.
    c.texture = textures && !dc.nonFinite && dc.array ? (hv.volume.nearest ? dc.point : dc.linear) : 0;
    c.voxelTexture = dc.array ? dc.point : 0;
    c.voxelTextureDims[0] = this->Dims[0];
    c.voxelTextureDims[1] = this->Dims[1];
    c.textureScale = dc.textureScale;
  }
  s.lighting = hv.lighting;
  return s;
}

const float* CUDARenderer::Internal::deviceDepth(const float* depth, size_t pixels)
{
  // Uploaded when it changes (geometry or view), else reused.
  if (!depth)
  {
    return nullptr;
  }
  const size_t P = pixels;
  if (!this->HaveDepth || this->LastDepth.size() != P ||
    std::memcmp(this->LastDepth.data(), depth, P * sizeof(float)) != 0)
  {
    this->Depth.resize(P);
    MCVOL_CUDA(cudaMemcpy(this->Depth.ptr, depth, P * sizeof(float), cudaMemcpyHostToDevice));
    this->LastDepth.assign(depth, depth + P);
    this->HaveDepth = true;
    this->OpenDepthPixels = size_t(std::count_if(depth, depth + P, [](float z) { return z > 0.f; }));
  }
  return this->Depth.ptr;
}

const float* CUDARenderer::Internal::deviceImportanceTables(const Scene& scene)
{
  const std::vector<float>& tables = scene.importanceTables();
  if (tables != this->LastImportanceTables)
  {
    this->ImportanceTables.resize(tables.size());
    MCVOL_CUDA(
      cudaMemcpy(this->ImportanceTables.ptr, tables.data(), tables.size() * sizeof(float), cudaMemcpyHostToDevice));
    this->LastImportanceTables = tables;
  }
  return this->ImportanceTables.ptr;
}

void CUDARenderer::Internal::deviceAccumulation(Accumulator& accum, size_t pixels, RenderLaunch& launch)
{
  // Continue the device image only if it is this Accumulator's, at its
  // sample count, with its sums; otherwise start from the host's. The
  // even-sample mean of the error estimate goes with it, when the
  // Accumulator keeps one (AccumEven: the device copy is in step).
  const size_t P = pixels;
  const bool wantEven = accum.hasEven();
  if (accum.pendingOnDevice() && this->AccumId != accum.id())
  {
    throw std::logic_error("mcvol: this Accumulator's image was left on the device (RenderSettings::readBack = "
                           "false) and has since been replaced by another Accumulator's; call readBack() before "
                           "rendering another Accumulator");
  }
  if (this->Accum.count != P || this->AccumSums.count != 4 * P)
  {
    this->Accum.resize(P);
    this->AccumSums.resize(4 * P);
    this->AccumId = 0;
  }
  if (wantEven && (this->Even.count != P || this->EvenSums.count != 4 * P))
  {
    this->Even.resize(P);
    this->EvenSums.resize(4 * P);
    this->AccumEven = false;
  }
  if (this->AccumId != accum.id() || this->AccumSamples != accum.samples() || (wantEven && !this->AccumEven) ||
    !this->AccumSumsCurrent)
  {
    if (accum.samples() == 0)
    {
      // The sums are not read at 0 samples (loadSum()).
      MCVOL_CUDA(cudaMemsetAsync(this->Accum.ptr, 0, this->Accum.bytes()));
      if (wantEven)
      {
        MCVOL_CUDA(cudaMemsetAsync(this->Even.ptr, 0, this->Even.bytes()));
      }
    }
    else
    {
      if (accum.pendingOnDevice())
      {
        // This image's mean is here without its sums (the ray marcher's):
        // to the host, where the sums are derived from it.
        MCVOL_CUDA(cudaMemcpy(accum.rgbaForOverwrite(), this->Accum.ptr, this->Accum.bytes(), cudaMemcpyDeviceToHost));
        accum.setPendingOnDevice(false);
      }
      const double* sums = accum.sums();
      MCVOL_CUDA(cudaMemcpy(this->Accum.ptr, accum.rgba(), this->Accum.bytes(), cudaMemcpyHostToDevice));
      MCVOL_CUDA(cudaMemcpy(this->AccumSums.ptr, sums, this->AccumSums.bytes(), cudaMemcpyHostToDevice));
      if (wantEven)
      {
        MCVOL_CUDA(cudaMemcpy(this->Even.ptr, accum.evenRGBA(), this->Even.bytes(), cudaMemcpyHostToDevice));
        MCVOL_CUDA(cudaMemcpy(this->EvenSums.ptr, accum.evenSums(), this->EvenSums.bytes(), cudaMemcpyHostToDevice));
      }
    }
    this->AccumId = accum.id();
  }
  // Renders without the split leave the device's even image behind.
  this->AccumEven = wantEven;
  this->AccumSumsCurrent = true;
  launch.accum = this->Accum.ptr;
  launch.sums = this->AccumSums.ptr;
  launch.even = wantEven ? this->Even.ptr : nullptr;
  launch.evenSums = wantEven ? this->EvenSums.ptr : nullptr;
}

Accumulator::ImportancePool& CUDARenderer::Internal::deviceImportance(
  const Scene& scene, const Camera& camera, Accumulator& accum, SceneView& s, size_t pixels, ImportanceLaunch& launch)
{
  // Tables uploaded when they change; the segment lists belong to one
  // Accumulator's image and restart with it (or when another Accumulator
  // rendered since: the lists of this one are gone).
  const size_t P = pixels;
  s.importance = scene.view().importance;
  setImportanceFrame(s, camera);
  s.importance.table = this->deviceImportanceTables(scene);
  Accumulator::ImportancePool& pool = accum.importancePool(false);
  if (this->Segments.count != P * size_t(kImportanceCapacity))
  {
    this->Segments.resize(P * size_t(kImportanceCapacity));
    this->SegmentCounts.resize(P);
    this->SegmentTotals.resize(P);
    this->PoolId = 0;
  }
  if (this->PoolId != accum.id() || pool.passes == 0)
  {
    MCVOL_CUDA(cudaMemsetAsync(this->SegmentCounts.ptr, 0, P));
    MCVOL_CUDA(cudaMemsetAsync(this->SegmentTotals.ptr, 0, P * sizeof(float)));
    pool.passes = 0;
    this->PoolId = accum.id();
  }
  pool.deviceBytes = this->Segments.bytes() + this->SegmentCounts.bytes() + this->SegmentTotals.bytes();
  launch.segments = this->Segments.ptr;
  launch.counts = this->SegmentCounts.ptr;
  launch.totals = this->SegmentTotals.ptr;
  launch.refinePass = pool.passes < s.importance.refinePasses ? pool.passes : -1;
  return pool;
}

void CUDARenderer::render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
  Accumulator& accum, RenderCounters* counters)
{
  Internal& in = *this->In;
  checkRenderArguments(camera, settings, accum);
  MCVOL_CUDA(cudaSetDevice(in.Device));
  in.sync(scene);

  SceneView s = in.renderView(scene, in.Sampling == CudaSampling::Texture);
  const CameraView cam = toView(camera);
  setRenderRates(s, settings, camera, cam);
  const bool lit = s.lighting.enabled;
  if (lit)
  {
    if (s.blend.mode == BlendMode::Composite)
    {
      throw std::invalid_argument("mcvol: the CUDA backend does not light post-render composite blending; use "
                                  "the CPU backend, or density, max or mix blending");
    }
    setLightingFrame(s, camera);
    // Lit, one piece of a split volume: the stand-in of the other pieces.
    in.linkOutside(scene, camera, s);
    in.linkShadowCaches(scene, s);
  }

  const size_t P = size_t(camera.width) * size_t(camera.height);
  RenderLaunch k;
  in.deviceAccumulation(accum, P, k);
  k.depth = in.deviceDepth(depth, P);
  k.previous = accum.samples();
  k.counters = in.Counters.ptr;
  k.light = s.outside && s.outsideExact ? &in.Outside.HostView : &s;
  k.block = in.Block;
  k.grid = imageGrid(k.block, camera.width, camera.height);
  const FrameParams fp = frameParams(settings, accum.samples());
  const bool optimized = scene.view().importance.enabled;
  ImportanceLaunch opt;
  Accumulator::ImportancePool* pool = optimized ? &in.deviceImportance(scene, camera, accum, s, P, opt) : nullptr;
  // The optimized kernel always counts: its overflow count is needed.
  const bool count = counters != nullptr || optimized;
  if (count)
  {
    MCVOL_CUDA(cudaMemsetAsync(in.Counters.ptr, 0, 9 * sizeof(unsigned long long)));
  }
  // Launched even with no active channel: the mean must still take the
  // added (transparent) samples.
  if (optimized)
  {
    launchOptimized(s.blend.mode, lit, s, cam, fp, k, opt);
  }
  else
  {
    if (lit && !count && in.DeferShadows && deferrableShadows(s, fp.sampler))
    {
      // Several samples per launch pair when the render asks for several:
      // setDeferredBatch()'s count, and more where few pixels can have rays
      // (a small image, or a depth mask whose 0 ends a ray before it starts:
      // the other processes' rows of a split image), up to the paths of a
      // whole 1024^2 image, since a launch lasts as long as its longest
      // paths however few it holds.
      size_t batch = 1;
      size_t open = P;
      if (settings.samplesPerPixel > 1)
      {
        if (depth)
        {
          open = in.OpenDepthPixels;
        }
        const size_t fill = std::max<size_t>(P, kFullLaunchPaths) / std::max<size_t>(open, 1);
        batch = std::min<size_t>(
          { kMaxDeferredBatch, size_t(settings.samplesPerPixel), std::max<size_t>(in.DeferredBatch, fill) });
        // The batch's queue within 1/16 of the device's memory (or one
        // entry per pixel, as one sample at a time takes).
        const size_t budget =
          std::max<size_t>(in.Props.totalGlobalMem / 16, P * sizeof(DeferredShadows));
        const size_t fits = budget / (std::max<size_t>(open, 1) * sizeof(DeferredShadows));
        batch = std::max<size_t>(1, std::min(batch, fits));
      }
      // One queue entry per path of a launch, kept at the most rendered.
      const size_t entries = std::max(P, batch * open);
      if (in.Deferred.count < entries)
      {
        in.Deferred.resize(entries);
      }
      in.DeferredCount.resize(1);
      k.deferred = in.Deferred.ptr;
      k.deferredCount = in.DeferredCount.ptr;
      k.deferredRoom = in.Deferred.count;
      if (batch > 1)
      {
        if (in.DeferredSlots.count < batch * P)
        {
          in.DeferredSlots.resize(batch * P);
        }
        k.deferredBatch = unsigned(batch);
        k.deferredSlots = in.DeferredSlots.ptr;
      }
    }
    launchRender(s.blend.mode, count, lit, in.PlainKernels && plainScene(s, *k.light), s, cam, fp, k);
  }
  MCVOL_CUDA(cudaGetLastError());

  accum.addSamples(uint32_t(settings.samplesPerPixel));
  in.AccumSamples = accum.samples();
  accum.setPendingOnDevice(true);
  if (pool && opt.refinePass >= 0)
  {
    ++pool->passes;
  }
  unsigned long long c[9] = {};
  if (count)
  {
    MCVOL_CUDA(cudaMemcpy(c, in.Counters.ptr, sizeof(c), cudaMemcpyDeviceToHost));
    if (pool)
    {
      pool->overflows += c[8];
    }
  }
  if (counters)
  {
    addCounters(*counters, c, uint64_t(camera.width) * uint64_t(camera.height) * uint64_t(settings.samplesPerPixel));
  }
  if (settings.readBack)
  {
    in.SkipEvenReadBack = !settings.readBackEven;
    this->readBack(accum);
    in.SkipEvenReadBack = false;
  }
}

void CUDARenderer::setConcurrentPilots(bool on)
{
  this->In->ConcurrentPilots = on;
}

bool CUDARenderer::concurrentPilots() const
{
  return this->In->ConcurrentPilots;
}

size_t CUDARenderer::Internal::startPilotRound(size_t images, size_t pixels, size_t jobs)
{
  const size_t P = pixels;
  // Room for the largest round chooseEstimator() makes at the default pilot
  // size from the first round on, so that no later round (e.g. the first
  // with a hint, which holds more candidates) grows the buffers and the
  // page-locked host copy: a reallocation costs more than the round.
  const size_t reserved = std::max(images, kReservedPilotImages) * P;
  this->PilotImages.resize(std::max(this->PilotImages.count, reserved));
  const size_t counterItems = 9 * (std::max<size_t>(jobs, kPilotStreams) + 1);
  this->PilotCounters.resize(std::max(this->PilotCounters.count, counterItems));
  // The streams are non-blocking and of the device's highest priority, and a
  // round uses no other stream: frames rendered ahead on the default stream
  // (ChoiceAhead) run beside the pilots, and the block scheduler gives the
  // pilots' blocks the SMs first as the frame's blocks finish, so the
  // round's latency stays the pilots'.
  if (this->PilotStreams.size() < kPilotStreams)
  {
    int least = 0, greatest = 0;
    MCVOL_CUDA(cudaDeviceGetStreamPriorityRange(&least, &greatest));
    while (this->PilotStreams.size() < kPilotStreams)
    {
      cudaStream_t st = nullptr;
      MCVOL_CUDA(cudaStreamCreateWithPriority(&st, cudaStreamNonBlocking, greatest));
      this->PilotStreams.push_back(st);
      cudaEvent_t e = nullptr;
      MCVOL_CUDA(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
      this->PilotEvents.push_back(e);
    }
  }
  const size_t streams = std::min(jobs, kPilotStreams);
  cudaStream_t first = this->PilotStreams[0];
  MCVOL_CUDA(cudaMemsetAsync(this->PilotImages.ptr, 0, images * P * sizeof(float4), first));
  const size_t counterCount = 9 * (jobs + 1); // the jobs' blocks and replicate 1's
  MCVOL_CUDA(cudaMemsetAsync(this->PilotCounters.ptr, 0, counterCount * sizeof(unsigned long long), first));
  MCVOL_CUDA(cudaEventRecord(this->PilotEvents[0], first));
  for (size_t k = 1; k < streams; ++k)
  {
    MCVOL_CUDA(cudaStreamWaitEvent(this->PilotStreams[k], this->PilotEvents[0], 0));
  }
  return reserved;
}

void CUDARenderer::Internal::launchPilots(const Scene& scene, const Camera& camera, const std::vector<PilotJob>& jobs)
{
  const size_t P = size_t(camera.width) * size_t(camera.height);
  const CameraView cam = toView(camera);
  const bool textures = this->Sampling == CudaSampling::Texture;
  RenderLaunch k;
  k.block = this->Block;
  const dim3 grid = imageGrid(k.block, camera.width, camera.height);
  size_t image = 0;
  for (size_t j = 0; j < jobs.size(); ++j)
  {
    const PilotJob& job = jobs[j];
    SceneView s = this->renderView(scene, textures);
    setRenderRates(s, job.settings, camera, cam);
    // One launch of all the job's one-sample images (FrameParams::
    // batchSamples): replicate r's sample k is the job's image r x n + k
    // (its seed job.seeds[r]), picked by blockIdx.z; replicate 0's counters
    // go to the job's block of 9, replicate 1's to the last block (not read).
    RenderSettings st = job.settings;
    st.samplesPerPixel = 1;
    st.seed = job.seeds[0];
    FrameParams fp = frameParams(st, 0u);
    const int n = job.checkpoints.back();
    fp.batchSamples = n;
    fp.batchSeed = job.seeds[1];
    fp.batchCounterOffset = int(9 * (jobs.size() - j));
    k.grid = dim3(grid.x, grid.y, unsigned(2 * n));
    k.accum = this->PilotImages.ptr + image * P;
    k.counters = this->PilotCounters.ptr + 9 * j;
    k.stream = this->PilotStreams[j % kPilotStreams];
    launchRender(scene.view().blend.mode, true, false, this->PlainKernels && plainScene(s, s), s, cam, fp, k);
    MCVOL_CUDA(cudaGetLastError());
    image += size_t(2 * n);
  }
  // The first stream waits for the others' launches, then copies back.
  cudaStream_t first = this->PilotStreams[0];
  for (size_t i = 1; i < std::min(jobs.size(), kPilotStreams); ++i)
  {
    MCVOL_CUDA(cudaEventRecord(this->PilotEvents[i], this->PilotStreams[i]));
    MCVOL_CUDA(cudaStreamWaitEvent(first, this->PilotEvents[i], 0));
  }
}

void CUDARenderer::Internal::pilotsToHost(size_t floats, size_t reservedFloats, size_t counterItems)
{
  // Page-locked host copies (a copy from pageable memory goes through a
  // staging buffer of the driver), grown to the reserved size at once.
  if (this->PilotHostCount < floats || this->PilotHostCount < reservedFloats)
  {
    if (this->PilotHost)
    {
      MCVOL_CUDA(cudaFreeHost(this->PilotHost));
      this->PilotHost = nullptr;
      this->PilotHostCount = 0;
    }
    MCVOL_CUDA(cudaMallocHost(reinterpret_cast<void**>(&this->PilotHost), reservedFloats * sizeof(float)));
    this->PilotHostCount = reservedFloats;
  }
  if (this->PilotHostCounterCount < this->PilotCounters.count)
  {
    if (this->PilotHostCounters)
    {
      MCVOL_CUDA(cudaFreeHost(this->PilotHostCounters));
      this->PilotHostCounters = nullptr;
      this->PilotHostCounterCount = 0;
    }
    MCVOL_CUDA(cudaMallocHost(
      reinterpret_cast<void**>(&this->PilotHostCounters), this->PilotCounters.count * sizeof(unsigned long long)));
    this->PilotHostCounterCount = this->PilotCounters.count;
  }
  cudaStream_t first = this->PilotStreams[0];
  MCVOL_CUDA(
    cudaMemcpyAsync(this->PilotHost, this->PilotImages.ptr, floats * sizeof(float), cudaMemcpyDeviceToHost, first));
  MCVOL_CUDA(cudaMemcpyAsync(this->PilotHostCounters, this->PilotCounters.ptr,
    counterItems * sizeof(unsigned long long), cudaMemcpyDeviceToHost, first));
  MCVOL_CUDA(cudaStreamSynchronize(first));
}

void CUDARenderer::renderPilots(const Scene& scene, const Camera& camera, std::vector<PilotJob>& jobs)
{
  Internal& in = *this->In;
  const SceneView& hv = scene.view();
  if (!in.ConcurrentPilots || hv.lighting.enabled || hv.importance.enabled || hv.blend.mode == BlendMode::Composite)
  {
    Renderer::renderPilots(scene, camera, jobs); // not what chooseEstimator() pilots: one after the other
    return;
  }
  const size_t images = checkPilotJobs(camera, jobs);
  if (jobs.empty())
  {
    return;
  }
  MCVOL_CUDA(cudaSetDevice(in.Device));
  in.sync(scene);
  const size_t P = size_t(camera.width) * size_t(camera.height);
  const size_t reserved = in.startPilotRound(images, P, jobs.size());
  in.launchPilots(scene, camera, jobs);
  in.pilotsToHost(images * P * 4, 4 * reserved, 9 * (jobs.size() + 1));
  foldPilotMeans(jobs, in.PilotHost, in.PilotHostCounters, P);
}

void CUDARenderer::readBack(Accumulator& accum)
{
  Internal& in = *this->In;
  const bool mine = in.AccumId == accum.id() && in.AccumSamples == accum.samples() &&
    in.Accum.count == size_t(accum.width()) * size_t(accum.height());
  if (!mine)
  {
    if (accum.pendingOnDevice())
    {
      throw std::logic_error("mcvol: this Accumulator's image is no longer on the device (another Accumulator "
                             "was rendered since); it cannot be read back");
    }
    return; // the host copy is current
  }
  MCVOL_CUDA(cudaSetDevice(in.Device));
  MCVOL_CUDA(cudaMemcpy(accum.rgbaForOverwrite(), in.Accum.ptr, in.Accum.bytes(), cudaMemcpyDeviceToHost));
  // The error estimate is computed on the host from both images: one more
  // copy of the image's size, only while the Accumulator keeps the estimate
  // (and, with RenderSettings::readBackEven off, only when readBackEven()
  // asks for it).
  accum.setPendingOnDevice(false);
  accum.setEvenPendingOnDevice(false);
  if (accum.hasEven() && in.AccumEven && in.Even.count == in.Accum.count)
  {
    if (in.SkipEvenReadBack)
    {
      accum.setEvenPendingOnDevice(true);
    }
    else
    {
      MCVOL_CUDA(cudaMemcpy(accum.evenRGBAForOverwrite(), in.Even.ptr, in.Even.bytes(), cudaMemcpyDeviceToHost));
    }
  }
  ++in.Updates.imageDownloads;
}

void CUDARenderer::readBackEven(Accumulator& accum)
{
  Internal& in = *this->In;
  if (!accum.evenPendingOnDevice())
  {
    return;
  }
  const bool mine = in.AccumId == accum.id() && in.AccumSamples == accum.samples() && in.AccumEven &&
    in.Even.count == size_t(accum.width()) * size_t(accum.height()) && accum.hasEven();
  if (mine)
  {
    MCVOL_CUDA(cudaSetDevice(in.Device));
    MCVOL_CUDA(cudaMemcpy(accum.evenRGBAForOverwrite(), in.Even.ptr, in.Even.bytes(), cudaMemcpyDeviceToHost));
    accum.setEvenPendingOnDevice(false);
  }
}
} // namespace mcvol
