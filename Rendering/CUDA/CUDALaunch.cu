// SPDX-License-Identifier: BSD-3-Clause
//
// One render on the GPU: the per-render scene view, the device accumulation
// image and depth buffer, the render kernel launch, the work counters and the
// read-back. The kernel is a launcher: the per-pixel work is renderPixel<Mode>()
// from the core (Integrator.h -> Tracking.h -> DDA.h, Sampling.h), the same
// functions the OpenMP backend runs, compiled for the device through
// MCVOL_HOST_DEVICE.
#include "CUDARenderKernels.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace mcvol
{
namespace
{
/**
 * The visibility optimization's kernel (paper 004): as renderKernel, with the
 * pixel's importance segment list refined first on the refining renders
 * (refinePass >= 0) and passed to the tracking. A kernel of its own, so
 * the unoptimized kernels stay exactly as they were.
 */
template <BlendMode Mode, bool Lit>
__global__ void renderOptimizedKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ FrameParams fp, const float* __restrict__ depth, float4* __restrict__ accum,
  float4* __restrict__ even, uint32_t previous, unsigned long long* __restrict__ counters,
  ImportanceSegment* __restrict__ segments, uint8_t* __restrict__ counts, float* __restrict__ totals, int refinePass)
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
    Vec4f evenSum;
    const Vec4f sum = renderPixel<Mode, Lit, true>(s, cam, fp, x, y, z, c, &ri, even ? &evenSum : nullptr);
    accumulatePixel(accum + p, sum, previous, fp.samplesPerPixel);
    if (even)
    {
      accumulateEvenPixel(even + p, evenSum, previous, fp.samplesPerPixel);
    }
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

/// Device copies of what the optimized kernel reads.
struct OptimizedLaunch
{
  ImportanceSegment* segments = nullptr;
  uint8_t* counts = nullptr;
  float* totals = nullptr;
  int refinePass = -1;
};

template <BlendMode Mode>
void launchOptimized(bool lit, dim3 grid, dim3 block, const SceneView& s, const CameraView& cam, const FrameParams& fp,
  const float* depth, float4* accum, float4* even, uint32_t previous, unsigned long long* counters,
  const OptimizedLaunch& o)
{
  if (lit)
  {
    renderOptimizedKernel<Mode, true><<<grid, block>>>(
      s, cam, fp, depth, accum, even, previous, counters, o.segments, o.counts, o.totals, o.refinePass);
  }
  else
  {
    renderOptimizedKernel<Mode, false><<<grid, block>>>(
      s, cam, fp, depth, accum, even, previous, counters, o.segments, o.counts, o.totals, o.refinePass);
  }
}

template <BlendMode Mode>
void launchRender(bool count, bool lit, bool plain, dim3 grid, dim3 block, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters, cudaStream_t stream = 0)
{
  // The unlit kernels contain none of the lighting code, the collision
  // kernels none of the expected-value estimator's (registers: ptxas); for
  // plain scenes, none of the pre-classified or cubic sampling either
  // (CUDALaunchPlain.cu).
  const int unlit = unlitEstimator(fp.estimator, Mode, lit, false, s.marchControlVariates);
  if (plain && !lit)
  {
    launchPlainUnlit(Mode, count, unlit, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
  }
  else if (lit)
  {
    if (count)
    {
      renderKernel<Mode, true, true><<<grid, block, 0, stream>>>(s, cam, fp, depth, accum, even, previous, counters);
    }
    else
    {
      renderKernel<Mode, false, true><<<grid, block, 0, stream>>>(s, cam, fp, depth, accum, even, previous, counters);
    }
  }
  else
  {
    launchUnlit<Mode>(unlit, count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
  }
}
/// launchRender() for the blend mode known at run time.
void launchRenderFor(BlendMode mode, bool count, bool lit, bool plain, dim3 grid, dim3 block, const SceneView& s,
  const CameraView& cam, const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters, cudaStream_t stream = 0)
{
  switch (mode)
  {
    case BlendMode::Max:
      launchRender<BlendMode::Max>(count, lit, plain, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
    case BlendMode::Mix:
      launchRender<BlendMode::Mix>(count, lit, plain, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
    case BlendMode::Composite:
      launchRender<BlendMode::Composite>(
        count, lit, plain, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
    case BlendMode::Density:
    default:
      launchRender<BlendMode::Density>(
        count, lit, plain, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
  }
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

void CUDARenderer::render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
  Accumulator& accum, RenderCounters* counters)
{
  Internal& in = *this->In;
  checkRenderArguments(camera, settings, accum);
  MCVOL_CUDA(cudaSetDevice(in.Device));
  in.sync(scene);

  SceneView s = in.renderView(scene, in.Sampling == CudaSampling::Texture);
  const SceneView& hv = scene.view();
  const CameraView cam = toView(camera);
  setRenderRates(s, settings, camera, cam);
  const bool lit = s.lighting.enabled;
  if (lit)
  {
    if (s.blend.mode == BlendMode::Composite)
    {
      throw std::invalid_argument("mcvol: lighting with post-render composite blending is not supported yet");
    }
    setLightingFrame(s, camera);
  }

  // Accumulation buffer: continue the device mean only if it is this
  // Accumulator's, at its sample count; otherwise start from the host's.
  // The even-sample mean of the error estimate goes with it, when the
  // Accumulator keeps one (AccumEven: the device copy is in step).
  const size_t P = size_t(camera.width) * size_t(camera.height);
  const bool wantEven = accum.hasEven();
  if (accum.pendingOnDevice() && in.AccumId != accum.id())
  {
    throw std::logic_error("mcvol: this Accumulator's image was left on the device (RenderSettings::readBack = "
                           "false) and has since been replaced by another Accumulator's; call readBack() before "
                           "rendering another Accumulator");
  }
  if (in.Accum.count != P)
  {
    in.Accum.resize(P);
    in.AccumId = 0;
  }
  if (wantEven && in.Even.count != P)
  {
    in.Even.resize(P);
    in.AccumEven = false;
  }
  if (in.AccumId != accum.id() || in.AccumSamples != accum.samples() || (wantEven && !in.AccumEven))
  {
    if (accum.samples() == 0)
    {
      MCVOL_CUDA(cudaMemsetAsync(in.Accum.ptr, 0, in.Accum.bytes()));
      if (wantEven)
      {
        MCVOL_CUDA(cudaMemsetAsync(in.Even.ptr, 0, in.Even.bytes()));
      }
    }
    else
    {
      MCVOL_CUDA(cudaMemcpy(in.Accum.ptr, accum.rgba(), in.Accum.bytes(), cudaMemcpyHostToDevice));
      if (wantEven)
      {
        MCVOL_CUDA(cudaMemcpy(in.Even.ptr, accum.evenRGBA(), in.Even.bytes(), cudaMemcpyHostToDevice));
      }
    }
    in.AccumId = accum.id();
  }
  // Renders without the split leave the device's even image behind.
  in.AccumEven = wantEven;
  float4* devEven = wantEven ? in.Even.ptr : nullptr;

  const float* devDepth = in.deviceDepth(depth, P);

  const FrameParams fp = frameParams(settings, accum.samples());
  // Visibility optimization: tables uploaded when they change; the segment
  // lists belong to one Accumulator's image and restart with it (or when
  // another Accumulator rendered since: the lists of this one are gone).
  const bool optimized = hv.importance.enabled;
  OptimizedLaunch opt;
  Accumulator::ImportancePool* pool = nullptr;
  if (optimized)
  {
    s.importance = hv.importance;
    setImportanceFrame(s, camera);
    s.importance.table = in.deviceImportanceTables(scene);
    pool = &accum.importancePool(false);
    if (in.Segments.count != P * size_t(kImportanceCapacity))
    {
      in.Segments.resize(P * size_t(kImportanceCapacity));
      in.SegmentCounts.resize(P);
      in.SegmentTotals.resize(P);
      in.PoolId = 0;
    }
    if (in.PoolId != accum.id() || pool->passes == 0)
    {
      MCVOL_CUDA(cudaMemsetAsync(in.SegmentCounts.ptr, 0, P));
      MCVOL_CUDA(cudaMemsetAsync(in.SegmentTotals.ptr, 0, P * sizeof(float)));
      pool->passes = 0;
      in.PoolId = accum.id();
    }
    pool->deviceBytes = in.Segments.bytes() + in.SegmentCounts.bytes() + in.SegmentTotals.bytes();
    opt.segments = in.Segments.ptr;
    opt.counts = in.SegmentCounts.ptr;
    opt.totals = in.SegmentTotals.ptr;
    opt.refinePass = pool->passes < s.importance.refinePasses ? pool->passes : -1;
  }
  const bool count = counters != nullptr || optimized;
  // Plain scenes (scalar channels, linear or nearest interpolation) take the
  // kernels compiled without the pre-classified and cubic sampling.
  bool plain = in.PlainKernels && !s.volume.cubic;
  for (int n = 0; n < s.volume.numChannels; ++n)
  {
    plain = plain && s.volume.channels[n].format == ChannelFormat::Scalar;
  }
  if (count)
  {
    MCVOL_CUDA(cudaMemsetAsync(in.Counters.ptr, 0, 9 * sizeof(unsigned long long)));
  }
  const dim3 block = in.Block;
  const dim3 grid((unsigned(camera.width) + block.x - 1) / block.x, (unsigned(camera.height) + block.y - 1) / block.y);
  const uint32_t previous = accum.samples();
  {
    // Launched even with no active channel: the mean must still take the
    // added (transparent) samples.
    if (optimized)
    {
      switch (s.blend.mode)
      {
        case BlendMode::Max:
          launchOptimized<BlendMode::Max>(
            lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, devEven, previous, in.Counters.ptr, opt);
          break;
        case BlendMode::Mix:
          launchOptimized<BlendMode::Mix>(
            lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, devEven, previous, in.Counters.ptr, opt);
          break;
        case BlendMode::Composite:
          launchOptimized<BlendMode::Composite>(
            lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, devEven, previous, in.Counters.ptr, opt);
          break;
        case BlendMode::Density:
        default:
          launchOptimized<BlendMode::Density>(
            lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, devEven, previous, in.Counters.ptr, opt);
          break;
      }
    }
    else
    {
      launchRenderFor(
        s.blend.mode, count, lit, plain, grid, block, s, cam, fp, devDepth, in.Accum.ptr, devEven, previous, in.Counters.ptr);
    }
    MCVOL_CUDA(cudaGetLastError());
  }
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

void CUDARenderer::renderPilots(const Scene& scene, const Camera& camera, std::vector<PilotJob>& jobs)
{
  Internal& in = *this->In;
  const SceneView& hv = scene.view();
  if (!in.ConcurrentPilots || hv.lighting.enabled || hv.importance.enabled || hv.blend.mode == BlendMode::Composite)
  {
    Renderer::renderPilots(scene, camera, jobs); // not what chooseEstimator() pilots: one after the other
    return;
  }
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
  if (jobs.empty())
  {
    return;
  }
  // MCVOL_PILOT_PROFILE set: each round's wall time split into its steps on
  // stderr (the benchmark's question of where a round's time goes; one more
  // synchronisation of the first pilot stream after the launches, so only
  // while measuring).
  static const bool profile = std::getenv("MCVOL_PILOT_PROFILE") != nullptr;
  using PilotClock = std::chrono::steady_clock;
  PilotClock::time_point tp[6];
  tp[0] = PilotClock::now();
  MCVOL_CUDA(cudaSetDevice(in.Device));
  in.sync(scene);
  const size_t P = size_t(camera.width) * size_t(camera.height);
  // Room for the largest round chooseEstimator() makes at the default pilot
  // size (16 candidates: expected value's 2 x 8 images and 15 marches' 2 x
  // 2) from the first round on, so that no later round (e.g. the first
  // with a hint, which holds more candidates) grows the buffers and the
  // page-locked host copy: on the H100 a round that grew them took 2-3 ms
  // more (Benchmarks/RESULTS.md, eighteenth session).
  constexpr size_t kReservedImages = 96;
  const size_t reserved = std::max(images, kReservedImages) * P;
  in.PilotImages.resize(std::max(in.PilotImages.count, reserved));
  const size_t counterItems = 9 * (std::max<size_t>(jobs.size(), 16) + 1);
  in.PilotCounters.resize(std::max(in.PilotCounters.count, counterItems));
  // A stream per job of the largest round chooseEstimator() makes (16
  // candidates), so that they run side by side; each job is one launch of
  // all its one-sample images (FrameParams::batchSamples: blockIdx.z picks
  // the replicate and the sample; before, one launch per image took 0.13-0.34
  // ms a round on the H100 to issue). The streams are non-blocking and of
  // the device's highest priority, and a round uses no other stream: frames
  // rendered ahead on the default stream (ChoiceAhead) run beside the
  // pilots, and the block scheduler gives the pilots' blocks the SMs first
  // as the frame's blocks finish, so the round's latency stays the pilots'.
  constexpr size_t kStreams = 16;
  if (in.PilotStreams.size() < kStreams)
  {
    int least = 0, greatest = 0;
    MCVOL_CUDA(cudaDeviceGetStreamPriorityRange(&least, &greatest));
    while (in.PilotStreams.size() < kStreams)
    {
      cudaStream_t st = nullptr;
      MCVOL_CUDA(cudaStreamCreateWithPriority(&st, cudaStreamNonBlocking, greatest));
      in.PilotStreams.push_back(st);
      cudaEvent_t e = nullptr;
      MCVOL_CUDA(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
      in.PilotEvents.push_back(e);
    }
  }
  const size_t streams = std::min(jobs.size(), kStreams);
  cudaStream_t first = in.PilotStreams[0];
  MCVOL_CUDA(cudaMemsetAsync(in.PilotImages.ptr, 0, images * P * sizeof(float4), first));
  const size_t counterCount = 9 * (jobs.size() + 1); // the jobs' blocks and replicate 1's
  MCVOL_CUDA(cudaMemsetAsync(in.PilotCounters.ptr, 0, counterCount * sizeof(unsigned long long), first));
  MCVOL_CUDA(cudaEventRecord(in.PilotEvents[0], first));
  for (size_t k = 1; k < streams; ++k)
  {
    MCVOL_CUDA(cudaStreamWaitEvent(in.PilotStreams[k], in.PilotEvents[0], 0));
  }

  tp[1] = PilotClock::now();
  const CameraView cam = toView(camera);
  const dim3 block = in.Block;
  const dim3 grid((unsigned(camera.width) + block.x - 1) / block.x, (unsigned(camera.height) + block.y - 1) / block.y);
  const bool textures = in.Sampling == CudaSampling::Texture;
  size_t image = 0;
  for (size_t j = 0; j < jobs.size(); ++j)
  {
    const PilotJob& job = jobs[j];
    SceneView s = in.renderView(scene, textures);
    setRenderRates(s, job.settings, camera, cam);
    bool plain = in.PlainKernels && !s.volume.cubic;
    for (int n = 0; n < s.volume.numChannels; ++n)
    {
      plain = plain && s.volume.channels[n].format == ChannelFormat::Scalar;
    }
    // One launch: replicate r's sample k is the job's image r x n + k (its
    // seed job.seeds[r]); replicate 0's counters go to the job's block of 9,
    // replicate 1's to the last block (not read).
    RenderSettings st = job.settings;
    st.samplesPerPixel = 1;
    st.seed = job.seeds[0];
    FrameParams fp = frameParams(st, 0u);
    const int n = job.checkpoints.back();
    fp.batchSamples = n;
    fp.batchSeed = job.seeds[1];
    fp.batchCounterOffset = int(9 * (jobs.size() - j));
    const dim3 batch(grid.x, grid.y, unsigned(2 * n));
    launchRenderFor(hv.blend.mode, true, false, plain, batch, block, s, cam, fp, nullptr, in.PilotImages.ptr + image * P,
      nullptr, 0u, in.PilotCounters.ptr + 9 * j, in.PilotStreams[j % kStreams]);
    MCVOL_CUDA(cudaGetLastError());
    image += size_t(2 * n);
  }
  // The first stream waits for the others' launches, then copies back.
  for (size_t k = 1; k < streams; ++k)
  {
    MCVOL_CUDA(cudaEventRecord(in.PilotEvents[k], in.PilotStreams[k]));
    MCVOL_CUDA(cudaStreamWaitEvent(first, in.PilotEvents[k], 0));
  }
  tp[2] = PilotClock::now();
  if (profile)
  {
    MCVOL_CUDA(cudaStreamSynchronize(first)); // the kernels' end, for the split
  }
  tp[3] = PilotClock::now();
  const size_t floats = images * P * 4;
  if (in.PilotHostCount < floats || in.PilotHostCount < 4 * reserved)
  {
    if (in.PilotHost)
    {
      MCVOL_CUDA(cudaFreeHost(in.PilotHost));
      in.PilotHost = nullptr;
      in.PilotHostCount = 0;
    }
    MCVOL_CUDA(cudaMallocHost(reinterpret_cast<void**>(&in.PilotHost), 4 * reserved * sizeof(float)));
    in.PilotHostCount = 4 * reserved;
  }
  if (in.PilotHostCounterCount < in.PilotCounters.count)
  {
    if (in.PilotHostCounters)
    {
      MCVOL_CUDA(cudaFreeHost(in.PilotHostCounters));
      in.PilotHostCounters = nullptr;
      in.PilotHostCounterCount = 0;
    }
    MCVOL_CUDA(cudaMallocHost(
      reinterpret_cast<void**>(&in.PilotHostCounters), in.PilotCounters.count * sizeof(unsigned long long)));
    in.PilotHostCounterCount = in.PilotCounters.count;
  }
  const float* host = in.PilotHost;
  MCVOL_CUDA(cudaMemcpyAsync(in.PilotHost, in.PilotImages.ptr, floats * sizeof(float), cudaMemcpyDeviceToHost, first));
  MCVOL_CUDA(cudaMemcpyAsync(in.PilotHostCounters, in.PilotCounters.ptr, counterCount * sizeof(unsigned long long),
    cudaMemcpyDeviceToHost, first));
  MCVOL_CUDA(cudaStreamSynchronize(first));
  const unsigned long long* c = in.PilotHostCounters;

  tp[4] = PilotClock::now();
  // Each replicate's means at its checkpoints, folded as render() folds a
  // chunk of samples into the running mean (accumulate()).
  image = 0;
  std::vector<float> sums(4 * P);
  for (size_t j = 0; j < jobs.size(); ++j)
  {
    PilotJob& job = jobs[j];
    const int n = job.checkpoints.back();
    for (int r = 0; r < 2; ++r)
    {
      job.means[r].clear();
      std::vector<float> mean(4 * P, 0.f);
      int done = 0;
      for (int upTo : job.checkpoints)
      {
        // The samples summed image by image: each pixel's samples are added
        // in the same order as pixel by pixel, but each image is read once,
        // in order (pixel by pixel, the fold of a 64-image round took 0.5
        // ms on the H100 machine's host).
        std::fill(sums.begin(), sums.end(), 0.f);
        for (int k = done; k < upTo; ++k)
        {
          const float* v = host + 4 * (image + size_t(k)) * P;
          for (size_t i = 0; i < 4 * P; ++i)
          {
            sums[i] += v[i];
          }
        }
        for (size_t p = 0; p < P; ++p)
        {
          const Vec4f sum{ sums[4 * p], sums[4 * p + 1], sums[4 * p + 2], sums[4 * p + 3] };
          accumulate(mean.data() + 4 * p, sum, uint32_t(done), upTo - done);
        }
        done = upTo;
        job.means[r].push_back(mean);
      }
      image += size_t(n);
    }
    job.counters = RenderCounters();
    addCounters(job.counters, c + 9 * j, uint64_t(P) * uint64_t(n));
  }
  if (profile)
  {
    tp[5] = PilotClock::now();
    auto ms = [&](int a, int b) { return std::chrono::duration<double, std::milli>(tp[b] - tp[a]).count(); };
    std::fprintf(stderr,
      "mcvol pilot round: jobs %zu images %zu pixels %zu | setup %.3f issue %.3f kernels %.3f copy %.3f "
      "fold %.3f total %.3f ms\n",
      jobs.size(), images, P, ms(0, 1), ms(1, 2), ms(2, 3), ms(3, 4), ms(4, 5), ms(0, 5));
  }
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
