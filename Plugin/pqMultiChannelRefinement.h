// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   pqMultiChannelRefinement
 * @brief   Refines multi-channel Monte Carlo volumes while the GUI is idle.
 *
 * Started with the plugin in the ParaView GUI. Whenever the event loop has
 * nothing else to do, it renders again every render view that shows a
 * visible "Multi-Channel Volume (Monte Carlo)" representation with
 * progressive refinement on whose image is not finished (the server-side
 * representation reports Converged once Maximum Total Samples is reached).
 * Each render adds Samples Per Render samples; user events are served
 * between renders, and any change (camera, property, transfer function)
 * starts the mapper's image over, so refinement simply resumes from there.
 *
 * Connected to a pvserver the client holds no data, and ParaView reads a
 * representation's information properties from the client's copy; the
 * progress is read on the server instead, through a
 * vtkMultiChannelProgressProbe proxy per representation, and its text is
 * handed to the client's copy, whose corner annotation then shows the
 * server's progress.
 *
 * Setting Edit Channel on the active representation opens the colour map
 * editor (the representation points it at the channel's functions).
 *
 * It also writes the active view's progress to the main window's status
 * line (samples, estimated PSNR, refining or converged).
 */
#ifndef pqMultiChannelRefinement_h
#define pqMultiChannelRefinement_h

#include <QMap>
#include <QObject>
#include <QPointer>
#include <QString>
#include <QTimer>

#include "vtkNew.h"
#include "vtkSmartPointer.h"

class vtkEventQtSlotConnect;
class vtkSMProxy;

class pqMultiChannelRefinement : public QObject
{
  Q_OBJECT
  typedef QObject Superclass;

public:
  pqMultiChannelRefinement(QObject* parent = nullptr);
  ~pqMultiChannelRefinement() override;

  void startup();
  void shutdown();

private Q_SLOTS:
  void refine();
  void watchActiveRepresentation();
  void openColorMapEditor();

private:
  Q_DISABLE_COPY(pqMultiChannelRefinement)
  // The status line: "Multi-Channel Volume: 64 samples, estimated PSNR
  // 41.2 dB, refining" for the active view's representation (the active
  // one where it is one of ours), or why nothing is drawn.
  static QString progressLine(vtkSMProxy* proxy, int samples, int converged, const char* status);
  void showStatus(const QString& line);
  QString LastStatus;
  vtkNew<vtkEventQtSlotConnect> Links;
  QTimer Timer;
  // Samples seen per representation proxy after the last render this class
  // asked for: no progress means there is nothing to refine (an error).
  QMap<void*, int> LastSamples;
  // Remote sessions: the probe that reads each representation proxy's
  // progress on the server (vtkMultiChannelProgressProbe).
  vtkSMProxy* progressProbe(vtkSMProxy* representation);
  QMap<void*, vtkSmartPointer<vtkSMProxy>> Probes;
};

#endif
