// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMultiChannelDemoSource
 * @brief   Generates mcvol's built-in multi-channel demo volumes.
 *
 * vtkMultiChannelDemoSource produces one of mcvol's built-in datasets as a
 * vtkImageData, deterministically (the same name, size and channel count give
 * the same values on every machine):
 *
 * - "figure3": three overlapping cubes (red, green, blue) whose densities fall
 *   linearly along +X, -X and -Y (Sahistan et al., Figure 3); 3 x float,
 *   64^3 by default.
 * - "microscopy": a fluorescence-microscopy-like phantom (membranes, nuclei,
 *   puncta); 3 x unsigned char, 128 x 128 x 40 by default.
 * - "cosmology": a log-normal dark-matter density and three correlated fields
 *   (baryon density, temperature, velocity magnitude); 4 x float, 64^3.
 * - "weather": a hurricane-like vortex with 12 fields (pressure, temperature,
 *   winds, vapour, hydrometeors); 12 x float, 100 x 100 x 20.
 *
 * The channels come out as separate single-component point arrays named after
 * the channels (SetSeparateArrays, default on) and, with SetInterleaved
 * (default on), also as one N-component point-scalars array named "channels"
 * whose component names are the channel names. The latter is what
 * vtkMultiChannelVolumeMapper reads by default. Large versions (for example
 * 4 x 512^3) are made with SetDimensions. The source generates the update
 * extent it is asked for, the same voxels as those of the whole volume, so
 * under ParaView's MPI engine each rank generates its own piece alone. The
 * separate arrays carry their ranges in VTK's range cache, so ParaView's data
 * information does not read billions of voxels again.
 *
 * Each channel has a suggested transfer function, defined over the channel's
 * data range normalised to [0, 1]; GetSuggestedTransferFunction maps it onto
 * the channel's actual range.
 *
 * An unknown dataset name or a bad size is reported with vtkErrorMacro and
 * the output is empty.
 *
 * @sa vtkMultiChannelVolumeMapper
 */

#ifndef vtkMultiChannelDemoSource_h
#define vtkMultiChannelDemoSource_h

#include "mcvolRenderingMonteCarloModule.h" // For export macro
#include "vtkImageAlgorithm.h"

#include <memory> // For std::unique_ptr

class vtkColorTransferFunction;
class vtkPiecewiseFunction;

class MCVOLRENDERINGMONTECARLO_EXPORT vtkMultiChannelDemoSource : public vtkImageAlgorithm
{
public:
  static vtkMultiChannelDemoSource* New();
  vtkTypeMacro(vtkMultiChannelDemoSource, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * Name of the dataset: "figure3", "microscopy", "cosmology" (default) or
   * "weather".
   */
  vtkSetStringMacro(Dataset);
  vtkGetStringMacro(Dataset);
  ///@}

  /**
   * Number of built-in datasets and their names.
   */
  static int GetNumberOfDatasets();
  static const char* GetDatasetName(int index);

  ///@{
  /**
   * Voxels per axis (each 1..8192). All zero (default) means the dataset's
   * default size.
   */
  vtkSetVector3Macro(Dimensions, int);
  vtkGetVector3Macro(Dimensions, int);
  ///@}

  ///@{
  /**
   * Number of channels (0..32). 0 (default) means the dataset's own count;
   * fewer drops the last channels; more repeats the channels with other
   * colours and opacity bands (as in Sahistan et al.'s channel-count study).
   */
  vtkSetClampMacro(NumberOfChannels, int, 0, 32);
  vtkGetMacro(NumberOfChannels, int);
  ///@}

  ///@{
  /**
   * Whether the output holds one N-component point-scalars array named
   * "channels" (default on).
   */
  vtkSetMacro(Interleaved, bool);
  vtkGetMacro(Interleaved, bool);
  vtkBooleanMacro(Interleaved, bool);
  ///@}

  ///@{
  /**
   * Whether the output holds one single-component point array per channel,
   * named after the channel (default on). With both this and Interleaved
   * off, Interleaved is used.
   */
  vtkSetMacro(SeparateArrays, bool);
  vtkGetMacro(SeparateArrays, bool);
  vtkBooleanMacro(SeparateArrays, bool);
  ///@}

  /**
   * Number of channels and name of channel i of the last output (updates the
   * source if needed; 0 / nullptr on error).
   */
  int GetNumberOfOutputChannels();
  const char* GetChannelName(int channel);

  /**
   * Data range of channel i of the last output, a piece's own range when a
   * piece was asked for (updates the source if needed). Returns false on
   * error or when the output is an empty piece.
   */
  bool GetChannelRange(int channel, double range[2]);

  /**
   * Fills `color` and `opacity` (either may be nullptr) with the suggested
   * transfer function of channel i, its control points mapped from the
   * normalised range onto the channel's data range, and sets *unitDistance
   * (may be nullptr) to the suggested opacity unit distance in world units.
   * Updates the source if needed. Returns false (and reports an error) for a
   * bad channel or a failed update.
   */
  bool GetSuggestedTransferFunction(
    int channel, vtkColorTransferFunction* color, vtkPiecewiseFunction* opacity, double* unitDistance);

  /**
   * The same, mapped onto `range` instead of the output's own data range.
   * When the output is a piece (the source generates the update extent
   * alone, so each MPI rank makes only its own part), pass the whole
   * volume's range, for example from ParaView's data information, so that
   * every rank classifies its piece alike. False (and an error) for a range
   * that is not finite or is reversed.
   */
  bool GetSuggestedTransferFunction(int channel, const double range[2], vtkColorTransferFunction* color,
    vtkPiecewiseFunction* opacity, double* unitDistance);

  /**
   * Suggested opacity unit distance of channel i in world units (0 on error).
   */
  double GetSuggestedUnitDistance(int channel);

protected:
  vtkMultiChannelDemoSource();
  ~vtkMultiChannelDemoSource() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* Dataset = nullptr;
  int Dimensions[3] = { 0, 0, 0 };
  int NumberOfChannels = 0;
  bool Interleaved = true;
  bool SeparateArrays = true;

private:
  vtkMultiChannelDemoSource(const vtkMultiChannelDemoSource&) = delete;
  void operator=(const vtkMultiChannelDemoSource&) = delete;

  bool UpdateForQuery();

  struct vtkInternals;
  std::unique_ptr<vtkInternals> Internals;
};

#endif
