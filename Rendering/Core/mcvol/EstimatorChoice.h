// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Renderer.h"

#include <string>
#include <vector>

namespace mcvol
{
/**
 * The automatic estimator choice: the estimator that reaches a given error
 * soonest, per scene. No estimator wins everywhere: the expected-value
 * estimator reaches a target sooner on thin, sparse data (cosmology,
 * weather), the unbiased march on dense data (microscopy), and the march's
 * best rate depends on the data too (Documentation/performance.md).
 * chooseEstimator() renders a small pilot image of the scene with each
 * candidate and keeps the one predicted to reach the target error (35 dB by
 * default) in the least time:
 *   frames = 1 if MSE(1) <= target; else, with checkpoints k = 1, 2, 4, ...,
 *   n (the pilot's samples) and a_k = log2(MSE(k/2) / MSE(k)) held to
 *   [1, 2] (log(MSE(k') / MSE(n)) / log(n / k') for a last step from k' to
 *   n that is not a doubling), the first checkpoint k with
 *   MSE(k) <= target gives frames = ceil((k/2) (MSE(k/2) / target)^(1/a_k))
 *   within (k/2, k]; if none, frames = ceil(n (MSE(n) / target)^(1/a_n)).
 *   With n = 2 that is max(2, ceil((MSE(1) / target)^(1/a))). time =
 *   frames x cost per sample,
 * MSE(k) the pilot's mean squared error after k samples per pixel, measured
 * from two replicates with independent scrambles (seeds): the squared
 * difference of their means is twice the MSE of one. The decay a is 1 for
 * independent samples; with Sobol' points a pixel's samples are negatively
 * correlated and the error falls faster, so a 1/N extrapolation from n
 * samples would overstate the frames needed. Unlike the image's half-buffer
 * estimate (Accumulator::estimatedMSE), which overstates the noise of
 * Sobol'-sampled images by an amount that differs between estimators,
 * replicates measure the noise of the very sequence the image uses. The
 * frame count's floor of 1 matters: the march's noise falls faster than its
 * cost grows, so without a target the highest rate would always win, while
 * a rate that is clean in one frame is all an image needs.
 *
 * The cost is not the pilot's wall time but a linear model of the work
 * counters the render reports (CostModel), so that the choice, and with it
 * the image, is the same for a fixed seed whatever the machine's load or the
 * thread count (the rule for Monte Carlo output). The model's weights are
 * fitted per backend to measured frame times (defaultCostModel()).
 *
 * The implementation is a folder of its own, Rendering/Core/EstimatorChoice/:
 * the candidates, their pilots, the cost model and the rate search.
 */
struct EstimatorCandidate
{
  Estimator estimator = Estimator::ExpectedValue;
  /// RenderSettings::marchSamplesPerVoxel for the unbiased march.
  float marchSamplesPerVoxel = 2.f;
  /// The unbiased march with control variates (trackControlMarch()) at this
  /// rate, whatever kMarchControlVariateRate says; false: the plain strata.
  /// Only at pixel centres, where the control variates apply.
  bool controlVariates = false;
};

/// Cost of one sample as a weighted sum of the work counters (nanoseconds
/// per item on the machine it was fitted on; only ratios matter).
struct CostModel
{
  double perRay = 0;
  double perDdaStep = 0;
  double perTentative = 0; ///< tentative collisions, and the march's strata
  double perChannelSample = 0;
  double cost(const RenderCounters& c) const;
};

/// The model fitted for the backend of that name (Renderer::name(): "cpu",
/// "cuda"); the CPU's for any other. Fitted by
/// Benchmarks/studies/fit_cost_model.py to the frame times of
/// `mcvol-bench --sections converge`.
CostModel defaultCostModel(const std::string& backendName);

/// The rates chooseEstimator() tries between the listed ones (refineRates)
/// are multiples of this.
constexpr double kChoiceRateStep = 1.0 / 16.0;

struct EstimatorChoiceSettings
{
  /// The pilot image's longer side in pixels: the camera's whole view at
  /// this size, its rays jittered (where the image's are) over one image
  /// pixel's footprint (Camera::jitterScale), not over the pilot pixel's,
  /// which would add the image's variation across many pixels to every
  /// candidate's noise and hide their differences. The whole view, not
  /// tiles of the image: the march's noise sits in few pixels (thin features
  /// across a stratum), which tiles miss, and then the prediction falls
  /// far short.
  int pilotSize = 48;
  /// Samples per pixel of each of a candidate's two replicates (at least
  /// 2): the first alone decides whether one frame suffices, all of them
  /// predict the frames beyond.
  int pilotSamples = 2;
  /// Samples per pixel of the expected-value candidate's replicates (the
  /// larger of this and pilotSamples), rendered in doublings: its Sobol'
  /// gain fades over the first samples, so its decay is measured between 4
  /// and 8 rather than 1 and 2; measured from 2 it predicts too few frames.
  /// The marches' gain does not fade as early, and 2 samples predict their
  /// frames. These pilots cost little: 2 x 8 samples of a 48-pixel image.
  int expectedValuePilotSamples = 8;
  /// The error the prediction aims at, as the MSE over premultiplied RGB
  /// (peak 1): 10^-3.5, i.e. 35 dB PSNR, by default. A mapper with a
  /// TargetError (an RMSE) aims at its square.
  double targetMSE = 3.1622776601683794e-4;
  /// The unbiased march's candidate rates (strata per voxel). The expected
  /// value estimator (with the settings' minSamplesPerVoxel) is always a
  /// candidate, and goes first. At pixel centres each rate is offered twice,
  /// with the plain strata and with control variates (trackControlMarch(),
  /// also below kMarchControlVariateRate), unless the base settings fix the
  /// variant (RenderSettings::marchControlVariates off: plain only;
  /// marchControlVariatesFrom 0: control variates only); with jittered
  /// pixels only the plain strata, which is what the march renders there.
  /// They are tried in ascending order; the search skips a variant's rate
  /// when the variant's rate before it cost as much per sample as the best
  /// prediction so far (a higher rate costs more per sample, and takes at
  /// least one). A prediction that rose does not stop it (see
  /// chooseEstimator()).
  /// Rates 3 and 4 serve tight targets on dense data with the plain strata,
  /// where one sample at 2 per voxel falls short. With the control variates
  /// (pixel centres, from kMarchControlVariateRate) the noise falls faster
  /// than the rate rises, and 1.25 and 1.5 per voxel fill the gap where 1 is
  /// just short of a target and 2 overshoots it
  /// (Documentation/performance.md). Where a lower rate already wins the
  /// higher ones are never rendered (the rules above).
  std::vector<float> marchRates = { 0.0625f, 0.125f, 0.25f, 0.5f, 1.f, 1.25f, 1.5f, 2.f, 3.f, 4.f };
  /// Try every rate (no early stop): the benchmark's --choice-all, to
  /// compare each prediction with the measured time.
  bool tryAllRates = false;
  /// After the rates above, try one rate between the highest rate of a
  /// variant that needs more than one frame and the next, which needs one:
  /// where MSE(1), interpolated log-log in the rate, is predicted to meet
  /// the target (rounded up to a multiple of kChoiceRateStep), if its
  /// interpolated cost is below the best prediction. Whole frames make the
  /// choice jump at such a boundary (see chooseEstimator()).
  bool refineRates = true;
  /// The rate between aims at MSE(1) = refineMargin x the target, and counts
  /// as one frame only where its own pilot says so too (else two, so the
  /// listed rate above it, which takes one, stays ahead). The pilots are a
  /// small image: a rate aimed at the target itself can meet it in the pilot
  /// and still need two frames in the full image.
  double refineMargin = 0.75;
  /// Candidates to render in the first round where the backend renders a
  /// round at once (Renderer::rendersPilotsAtOnce), up to 16 with the
  /// first round's own: typically the previous choice's trials
  /// (EstimatorChoice::hint()), which the search after a transfer-function
  /// edit will likely reach again. A hinted rate between two listed ones is
  /// taken where the search plans that very rate. Only the wall time
  /// depends on it: the search takes a rendered result only where it
  /// reaches that candidate, so the trials and the choice are the same with
  /// any hint or none (and with a backend that renders one after the other
  /// the hint is not used).
  std::vector<EstimatorCandidate> hint;
  /// Use `model` instead of defaultCostModel(renderer.name()) (the
  /// benchmark's --cost-model, to try a fit without rebuilding).
  bool customModel = false;
  CostModel model;
};

/**
 * The estimator a render of `scene` with `settings` runs for its camera
 * rays: settings.estimator, except where the scene keeps the collision
 * estimator (the visibility optimization, composite blending, and the
 * unbiased march asked for a lit scene; unlitEstimator() in Integrator.h,
 * the kernels' own rule).
 */
Estimator effectiveEstimator(const Scene& scene, const RenderSettings& settings);
/// "Collision", "ExpectedValue", "UnbiasedMarch(R)" with R strata per
/// voxel (the plain strata), or "UnbiasedMarch(R, control variates)": the
/// names the choice's report and the mapper use.
std::string estimatorName(Estimator estimator, float marchSamplesPerVoxel, bool controlVariates = false);

/// `base` with candidate `c`'s estimator, rate and (at pixel centres, i.e.
/// unless base.jitterPixels and camera.jitterScale > 0) march variant: what
/// chooseEstimator() renders the candidate with, and the image's settings
/// when it is chosen.
RenderSettings candidateSettings(const RenderSettings& base, const Camera& camera, const EstimatorCandidate& c);

/// The pilot's view: `camera` with its longer side at most `pilotSize`
/// pixels (the rays unproject normalised device coordinates, so only the
/// pixel counts change), its jitter scaled to one image pixel's footprint
/// (EstimatorChoiceSettings::pilotSize says why).
Camera pilotCamera(const Camera& camera, int pilotSize);

/// One candidate's pilot.
struct EstimatorTrial
{
  EstimatorCandidate candidate;
  double firstFrameMSE = 0; ///< MSE of one sample per pixel (RGB, mean over pixels)
  int pilotSamples = 0;     ///< n: samples per pixel of each replicate
  double variance = 0;      ///< n x MSE(n)
  double decay = 1;         ///< a: MSE(N) ~ N^-a through MSE(n / 2) and MSE(n), held to [1, 2]
  double frames = 0;        ///< predicted samples per pixel to the target (see chooseEstimator)
  double costPerSample = 0; ///< the model's cost of one sample of one pixel
  double score = 0;         ///< frames x cost: the predicted time to the target (model units)
  /// A rate between two listed ones (EstimatorChoiceSettings::refineRates).
  bool refined = false;
  RenderCounters counters;
};

struct EstimatorChoice
{
  /// False where no pilot ran: where the estimator does not matter (the
  /// visibility optimization and composite blending always take the
  /// collision estimator), `settings` is the input; lit scenes take the
  /// expected-value estimator of lit camera rays (traceLitExpected()).
  bool applies = false;
  /// The input settings with the chosen estimator (and march rate; at pixel
  /// centres also the march's variant: marchControlVariates, and
  /// marchControlVariatesFrom 0 for control variates).
  RenderSettings settings;
  std::vector<EstimatorTrial> trials;
  int chosen = -1;    ///< index into trials
  double seconds = 0; ///< wall time of the pilots (reported, not used)
  /// Renderer::renderPilots() calls (rounds) and the candidates rendered in
  /// them: more than trials.size() where a round rendered ahead a rate the
  /// search did not reach (Renderer::rendersPilotsAtOnce).
  int rounds = 0;
  int rendered = 0;
  /// One line per candidate, the chosen one marked.
  std::string report() const;
  /// "ExpectedValue" or "UnbiasedMarch(1)" (rate in parentheses).
  std::string chosenName() const;
  /// The candidates of `trials`: the hint for the next choice of a scene
  /// like this one (EstimatorChoiceSettings::hint).
  std::vector<EstimatorCandidate> hint() const;
  /// The chosen trial's candidate (expected value where none was chosen):
  /// the next choice's ChoiceAhead::candidate.
  EstimatorCandidate chosenCandidate() const;
};

/**
 * Renders the pilots on `renderer` (the backend that will render the image:
 * the cost model is its own; Renderer::renderPilots, in rounds, with the
 * rates the search will most likely reach rendered ahead where the backend
 * renders a round at once) through `camera` scaled to settings.pilotSize,
 * without depth (geometry is not in the pilot), each
 * candidate as two replicates with seeds derived from `base`'s, with its
 * sampler, and picks the lowest score; ties go to the earlier candidate
 * (expected value first), so images with no noise at all (nothing visible)
 * keep the expected-value estimator. Throws what the renderer throws,
 * std::invalid_argument for a pilotSamples below 2, a target that is not
 * positive, or a march rate that is not positive and finite.
 */
EstimatorChoice chooseEstimator(Renderer& renderer, const Scene& scene, const Camera& camera,
  const RenderSettings& base, const EstimatorChoiceSettings& choice = EstimatorChoiceSettings());

/**
 * The image's first frames rendered while the pilots run, with the estimator
 * the choice will most likely pick again (after a transfer-function edit,
 * the previous choice's: EstimatorChoice::chosenCandidate()). A pilot round
 * is a few thousand long rays, bound by the slowest one's latency, while a
 * frame fills the GPU: a device backend runs both at once (CUDARenderer:
 * the frames on the default stream, the pilots on streams of higher
 * priority that never wait for it). Where the choice is `candidate`, the
 * frames are the image's first ones, exactly what rendering them after the
 * choice gives (the same settings and seeds); where it is not, they are
 * dropped (`accum` reset) and the caller renders the chosen estimator's.
 * The choice itself does not depend on them.
 */
struct ChoiceAhead
{
  EstimatorCandidate candidate;
  /// render() calls of base.samplesPerPixel samples each (at least 1).
  int renders = 1;
  /// The image's depth (Renderer::render's), or null.
  const float* depth = nullptr;
  /// The image; it must hold no samples yet. Null: nothing is rendered ahead.
  Accumulator* accum = nullptr;
  /// Out: the frames were rendered (the backend renders pilots at once,
  /// Renderer::rendersPilotsAtOnce, and the estimator choice applies to the
  /// scene).
  bool rendered = false;
  /// Out: the choice is `candidate`, and `accum` holds the frames (left on
  /// the device: RenderSettings::readBack off). False with `rendered`: they
  /// were dropped and `accum` is reset.
  bool kept = false;
};

/// chooseEstimator() with `ahead`'s frames rendered during the pilots
/// (ChoiceAhead). Throws std::invalid_argument where ahead.accum holds
/// samples or ahead.renders is below 1, and what chooseEstimator() throws.
EstimatorChoice chooseEstimator(Renderer& renderer, const Scene& scene, const Camera& camera,
  const RenderSettings& base, const EstimatorChoiceSettings& choice, ChoiceAhead& ahead);
} // namespace mcvol
