// SPDX-License-Identifier: BSD-3-Clause
#include "pqMultiChannelRefinement.h"

#include "pqActiveObjects.h"
#include "pqApplicationCore.h"
#include "pqColorMapEditor.h"
#include "pqDataRepresentation.h"
#include "pqCoreUtilities.h"
#include "pqRenderView.h"
#include "pqRepresentation.h"
#include "pqServer.h"
#include "pqServerManagerModel.h"
#include "vtkCommand.h"
#include "vtkEventQtSlotConnect.h"
#include "vtkMultiChannelVolumeRepresentation.h"
#include "vtkSMProperty.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"
#include "vtkSMSessionProxyManager.h"

#include <QApplication>
#include <QDockWidget>
#include <QMainWindow>
#include <QStatusBar>

#include <algorithm>
#include <cstring>
#include <string>

namespace
{
const char* const kRepresentationType = "Multi-Channel Volume (Monte Carlo)";

// The representation ParaView shows (UniformGridRepresentation) holds ours
// as a subproxy and exposes its properties; an exposed property belongs to
// the subproxy (vtkSMProxy::GetSubProxy is not public).
vtkSMProxy* multiChannelSubproxy(vtkSMProxy* representation)
{
  vtkSMProperty* ours = representation->GetProperty("ChannelBlendMode");
  return ours ? ours->GetParent() : nullptr;
}
}

//------------------------------------------------------------------------------
pqMultiChannelRefinement::pqMultiChannelRefinement(QObject* parentObject)
  : Superclass(parentObject)
{
  // Interval 0: fires whenever the event loop is idle, after pending events.
  this->Timer.setInterval(0);
  this->Timer.setSingleShot(false);
  QObject::connect(&this->Timer, &QTimer::timeout, this, &pqMultiChannelRefinement::refine);
}

//------------------------------------------------------------------------------
pqMultiChannelRefinement::~pqMultiChannelRefinement() = default;

//------------------------------------------------------------------------------
void pqMultiChannelRefinement::startup()
{
  this->Timer.start();
  QObject::connect(&pqActiveObjects::instance(),
    QOverload<pqRepresentation*>::of(&pqActiveObjects::representationChanged), this,
    &pqMultiChannelRefinement::watchActiveRepresentation);
  this->watchActiveRepresentation();
}

//------------------------------------------------------------------------------
void pqMultiChannelRefinement::watchActiveRepresentation()
{
  // Edit Channel (ActiveChannel) of the active representation opens the
  // colour map editor, which the representation has pointed at the channel.
  this->Links->Disconnect();
  pqDataRepresentation* repr = pqActiveObjects::instance().activeRepresentation();
  vtkSMProxy* proxy = repr ? repr->getProxy() : nullptr;
  vtkSMProperty* active = proxy ? proxy->GetProperty("ActiveChannel") : nullptr;
  if (active)
  {
    this->Links->Connect(active, vtkCommand::ModifiedEvent, this, SLOT(openColorMapEditor()));
  }
}

//------------------------------------------------------------------------------
void pqMultiChannelRefinement::openColorMapEditor()
{
  pqDataRepresentation* repr = pqActiveObjects::instance().activeRepresentation();
  vtkSMProxy* proxy = repr ? repr->getProxy() : nullptr;
  if (!proxy || !proxy->GetProperty("ActiveChannel") ||
    vtkSMPropertyHelper(proxy, "ActiveChannel").GetAsInt() < 0)
  {
    return;
  }
  QWidget* window = pqCoreUtilities::mainWidget();
  const QList<pqColorMapEditor*> editors =
    window ? window->findChildren<pqColorMapEditor*>() : QList<pqColorMapEditor*>();
  for (pqColorMapEditor* editor : editors)
  {
    if (auto* dock = qobject_cast<QDockWidget*>(editor->parentWidget()))
    {
      dock->show();
      dock->raise();
    }
  }
}

//------------------------------------------------------------------------------
void pqMultiChannelRefinement::shutdown()
{
  this->Timer.stop();
  this->Links->Disconnect();
}

//------------------------------------------------------------------------------
vtkSMProxy* pqMultiChannelRefinement::progressProbe(vtkSMProxy* representation)
{
  auto found = this->Probes.find(representation);
  if (found != this->Probes.end())
  {
    return found.value();
  }
  vtkSMProxy* ours = multiChannelSubproxy(representation);
  vtkSMSessionProxyManager* pxm = representation->GetSessionProxyManager();
  vtkSmartPointer<vtkSMProxy> probe;
  if (ours && pxm)
  {
    probe.TakeReference(pxm->NewProxy("mcvol_misc", "MultiChannelProgressProbe"));
  }
  if (probe)
  {
    vtkSMPropertyHelper(probe, "Representation").Set(ours);
    probe->UpdateVTKObjects();
  }
  this->Probes[representation] = probe;
  return probe;
}

//------------------------------------------------------------------------------
void pqMultiChannelRefinement::refine()
{
  pqApplicationCore* core = pqApplicationCore::instance();
  if (!core || QApplication::mouseButtons() != Qt::NoButton || QApplication::activeModalWidget())
  {
    // Interaction renders by itself; a modal dialog wants the CPU. Look
    // again later (an interval of 0 would spin while the dialog is open).
    this->Timer.setInterval(100);
    return;
  }
  bool rendered = false;
  QString statusLine;
  QMap<void*, vtkSmartPointer<vtkSMProxy>> probesInUse;
  const QList<pqRenderView*> views = core->getServerManagerModel()->findItems<pqRenderView*>();
  for (pqRenderView* view : views)
  {
    bool needsRender = false;
    const bool remote = view->getServer() && view->getServer()->isRemote();
    for (pqRepresentation* repr : view->getRepresentations())
    {
      vtkSMProxy* proxy = repr ? repr->getProxy() : nullptr;
      if (!proxy || !repr->isVisible() || !proxy->GetProperty("Representation"))
      {
        continue;
      }
      // The representation's properties are exposed by the composite
      // representation proxy ParaView shows (UniformGridRepresentation).
      const char* type = vtkSMPropertyHelper(proxy, "Representation").GetAsString();
      if (!type || strcmp(type, kRepresentationType) != 0 || !proxy->GetProperty("Converged") ||
        vtkSMPropertyHelper(proxy, "ProgressiveRefinement").GetAsInt() == 0)
      {
        continue;
      }
      // Where the data is: the representation itself in builtin mode, its
      // probe on the server of a remote session.
      vtkSMProxy* info = proxy;
      if (remote)
      {
        info = this->progressProbe(proxy);
        if (!info)
        {
          continue;
        }
        probesInUse[proxy] = info;
      }
      info->UpdatePropertyInformation();
      const int converged = vtkSMPropertyHelper(info, "Converged").GetAsInt();
      const int samples = vtkSMPropertyHelper(info, "TotalSamples").GetAsInt();
      const char* status = vtkSMPropertyHelper(info, "ChannelStatus").GetAsString();
      if (view == pqActiveObjects::instance().activeView() &&
        (statusLine.isEmpty() || repr == pqActiveObjects::instance().activeRepresentation()))
      {
        statusLine = progressLine(info, samples, converged, status);
      }
      bool annotationChanged = false;
      if (remote)
      {
        // The client's copy draws the corner annotation: give it the
        // server's words.
        vtkSMProxy* ours = multiChannelSubproxy(proxy);
        auto* local =
          vtkMultiChannelVolumeRepresentation::SafeDownCast(ours ? ours->GetClientSideObject() : nullptr);
        const char* text = vtkSMPropertyHelper(info, "ProgressText").GetAsString();
        if (local)
        {
          const std::string words = text ? text : "";
          annotationChanged = local->GetRemoteProgressSummary() != words;
          local->SetRemoteProgressSummary(words);
        }
      }
      auto last = this->LastSamples.find(proxy);
      const bool stalled = last != this->LastSamples.end() && last.value() == samples;
      if (!converged && (!status || !*status) && !stalled)
      {
        needsRender = true;
        this->LastSamples[proxy] = samples;
      }
      else if (!stalled || converged)
      {
        this->LastSamples.remove(proxy);
      }
      // A finished image whose annotation still shows the last step's words.
      needsRender = needsRender || annotationChanged;
    }
    if (needsRender)
    {
      view->forceRender();
      rendered = true;
    }
  }
  // Probes of representations that are gone or hidden go too.
  this->Probes.swap(probesInUse);
  this->showStatus(statusLine);
  // Nothing to do: look again a little later rather than spin.
  this->Timer.setInterval(rendered ? 0 : 100);
}

//------------------------------------------------------------------------------
QString pqMultiChannelRefinement::progressLine(vtkSMProxy* proxy, int samples, int converged, const char* status)
{
  if (status && *status)
  {
    return QString("Multi-Channel Volume: %1").arg(status);
  }
  if (samples <= 0)
  {
    return QString();
  }
  const double psnr = vtkSMPropertyHelper(proxy, "EstimatedPSNR").GetAsDouble();
  QString line = QString("Multi-Channel Volume: %1 samples").arg(samples);
  if (psnr > 0.0)
  {
    line += QString(", estimated PSNR %1 dB").arg(psnr, 0, 'f', 1);
  }
  line += converged ? ", converged" : ", refining";
  return line;
}

//------------------------------------------------------------------------------
void pqMultiChannelRefinement::showStatus(const QString& line)
{
  if (line == this->LastStatus)
  {
    return;
  }
  auto* window = qobject_cast<QMainWindow*>(pqCoreUtilities::mainWidget());
  if (window && window->statusBar())
  {
    if (line.isEmpty())
    {
      window->statusBar()->clearMessage();
    }
    else
    {
      window->statusBar()->showMessage(line);
    }
  }
  this->LastStatus = line;
}
