// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkSMMultiChannelVolumeRepresentationProxy
 * @brief   Client-side proxy of the multi-channel volume representation.
 *
 * Gives every channel a transfer function from ParaView's transfer function
 * manager, so that channels are edited like any coloured array: with the
 * colour map editor, GetColorTransferFunction/GetOpacityTransferFunction in
 * Python, presets, and saved in state files.
 *
 * - Channels from arrays: channel "density" uses the transfer functions of
 *   the array "density" (the ones colouring by "density" shows).
 * - Channels from the components of one array: component k of "stains" uses
 *   the transfer functions named "stains:k" (ChannelFunctionName()).
 *
 * Whenever the channel list changes, ChannelLookupTables is set to these
 * lookup tables (each carries its opacity function). A transfer function the
 * manager creates here is fitted to the channel's data range and given a
 * preset of its own (Reds, Greens, Blues, ...), so channels are told apart
 * from the start. State files keep the list as saved (nothing is derived
 * while a state is loaded).
 *
 * ParaView delivers a repeatable proxy property to the server as a set
 * ordered by global id, so ChannelLookupTableIndices (not saved in states)
 * tells the server which lookup table each channel uses; it is recomputed
 * before every push.
 *
 * ActiveChannel (-1: none) puts channel k's functions in the
 * representation's LookupTable and ScalarOpacityFunction, which is what
 * ParaView's colour map editor edits.
 */
#ifndef vtkSMMultiChannelVolumeRepresentationProxy_h
#define vtkSMMultiChannelVolumeRepresentationProxy_h

#include "mcvolParaViewRepresentationModule.h" // For export macro
#include "vtkSMRepresentationProxy.h"
#include "vtkWeakPointer.h" // For vtkWeakPointer

#include <map>    // For std::map
#include <string> // For std::string
#include <utility> // For std::pair
#include <vector> // For std::vector

class MCVOLPARAVIEWREPRESENTATION_EXPORT vtkSMMultiChannelVolumeRepresentationProxy
  : public vtkSMRepresentationProxy
{
public:
  static vtkSMMultiChannelVolumeRepresentationProxy* New();
  vtkTypeMacro(vtkSMMultiChannelVolumeRepresentationProxy, vtkSMRepresentationProxy);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /**
   * Name of the transfer functions of component `component` of `array` when
   * channels are the components of one array ("array:component").
   */
  static std::string ChannelFunctionName(const char* array, int component);

  /**
   * The transfer-function names of the channels, in order, as the current
   * property values select them (component channels need the input's data
   * information for the number of components).
   */
  std::vector<std::string> GetChannelFunctionNames();

  /**
   * Sets ChannelLookupTables from the transfer function manager for the
   * current channels. Called whenever a channel property changes; call it
   * after changing channels with the property modified events blocked.
   * Returns the number of channels.
   */
  int UpdateChannelLookupTables();

  void UpdateVTKObjects() override;

  /**
   * Watches the view: after each of its renders the information properties
   * (TotalSamples, EstimatedPSNR, Converged, ProgressText, ...) are read
   * again, so that Python's rep.TotalSamples is the current value.
   */
  void ViewUpdated(vtkSMProxy* view) override;

protected:
  vtkSMMultiChannelVolumeRepresentationProxy();
  ~vtkSMMultiChannelVolumeRepresentationProxy() override;

  void SetPropertyModifiedFlag(const char* name, int flag) override;
  void ShowActiveChannel();
  /**
   * Sets ChannelLookupTableIndices from ChannelLookupTables: ParaView sends a
   * repeatable proxy property to the server as a set ordered by global id,
   * so each channel's position in that set is sent alongside. Returns true
   * when the value changed.
   */
  bool SyncLookupTableIndices();

  /**
   * When the representation is first shown with no channel chosen: the
   * input's channels. A file's active channels (mcvol_display/<array> field
   * arrays, as the OME-Zarr reader writes them), else the components of the
   * input's one multi-component point array ("Components of One Array"),
   * else every single-component point array (at most 32).
   */
  void ChooseDefaultChannels();
  /**
   * A new channel's transfer functions, as mcvol-render's defaults: a ramp
   * of the channel's colour over its robust range (or the file's colour and
   * window), transparent below 15 % of the range (below the window's
   * start), opacity 0.3 per 4 voxels at the top.
   */
  void ApplyDefaultFunctions(vtkSMProxy* lut, vtkSMProxy* pwf, const char* array, int component, int channel,
    int channels);
  /// The robust range of a point array's component, from the server.
  bool DefaultRange(const char* array, int component, double range[2]);

  bool InUpdate = false;
  bool DefaultChannelsChosen = false;
  bool DefaultRangesFetched = false;
  std::map<std::string, std::pair<double, double>> DefaultRanges;
  void ViewRendered();
  vtkWeakPointer<vtkSMProxy> ObservedView;
  unsigned long ViewObserver = 0;


private:
  vtkSMMultiChannelVolumeRepresentationProxy(const vtkSMMultiChannelVolumeRepresentationProxy&) = delete;
  void operator=(const vtkSMMultiChannelVolumeRepresentationProxy&) = delete;
};

#endif
