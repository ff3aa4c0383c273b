// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkMultiChannelProgressProbe
 * @brief Reads a multi-channel volume representation's progress where it renders.
 *
 * ParaView reads a representation's information properties from the client
 * whenever the representation also lives there, and the client of a
 * pvserver holds no data: its copy reports no samples. This object lives on
 * the servers only (its proxy, "MultiChannelProgressProbe" in the plugin's
 * "mcvol_misc" group, has processes="dataserver"), points at the server's
 * copy of the representation through a proxy property, and so its
 * information properties carry the rendering process's samples, estimated
 * PSNR, convergence and annotation text to the client. In builtin mode the
 * client and the server are one process and it reads the same object.
 */
#ifndef vtkMultiChannelProgressProbe_h
#define vtkMultiChannelProgressProbe_h

#include "mcvolParaViewRepresentationModule.h" // for export macro
#include "vtkObject.h"
#include "vtkWeakPointer.h" // the representation is not owned

#include <string>

class vtkMultiChannelVolumeRepresentation;

class MCVOLPARAVIEWREPRESENTATION_EXPORT vtkMultiChannelProgressProbe : public vtkObject
{
public:
  static vtkMultiChannelProgressProbe* New();
  vtkTypeMacro(vtkMultiChannelProgressProbe, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The representation to read (not owned; nullptr reads nothing).
  void SetRepresentation(vtkMultiChannelVolumeRepresentation* representation);

  ///@{
  /// The representation's values, as its information properties of the
  /// same names give them in the process that renders: -1 samples, -1 dB,
  /// not converged and empty texts without a representation.
  int GetTotalSamples();
  double GetEstimatedPSNR();
  int GetConverged();
  const char* GetProgressText();
  const char* GetChannelStatus();
  ///@}

protected:
  vtkMultiChannelProgressProbe();
  ~vtkMultiChannelProgressProbe() override;

  vtkWeakPointer<vtkMultiChannelVolumeRepresentation> Representation;
  std::string Text;

private:
  vtkMultiChannelProgressProbe(const vtkMultiChannelProgressProbe&) = delete;
  void operator=(const vtkMultiChannelProgressProbe&) = delete;
};

#endif
