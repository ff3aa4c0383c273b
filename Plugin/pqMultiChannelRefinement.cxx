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
#include "vtkSMProperty.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"

#include <QApplication>
#include <QDockWidget>
#include <QMainWindow>
#include <QStatusBar>

#include <algorithm>
#include <cstring>

namespace
{
const char* const kRepresentationType = "Multi-Channel Volume (Monte Carlo)";
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
void pqMultiChannelRefinement::viewRendered()
{
  void* view = this->sender();
  if (this->Pending.value(view, false))
  {
    this->OwnRenders[view] = this->OwnRenders.value(view, 0) + 1;
  }
  else
  {
    // A render we did not ask for: the image may have started over.
    this->OwnRenders[view] = 0;
  }
  this->Pending[view] = false;
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
  const QList<pqRenderView*> views = core->getServerManagerModel()->findItems<pqRenderView*>();
  for (pqRenderView* view : views)
  {
    bool needsRender = false;
    const bool remote = view->getServer() && view->getServer()->isRemote();
    if (remote && !this->Pending.contains(view))
    {
      // Count renders: ours are flagged in Pending before they start.
      QObject::connect(view, &pqView::endRender, this, &pqMultiChannelRefinement::viewRendered,
        Qt::UniqueConnection);
      this->Pending[view] = false;
    }
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
      if (remote)
      {
        const int spp = std::max(1, vtkSMPropertyHelper(proxy, "SamplesPerRender").GetAsInt());
        const int maximum = vtkSMPropertyHelper(proxy, "MaximumTotalSamples").GetAsInt();
        const int wanted = maximum > 0 ? (maximum + spp - 1) / spp - 1 : 1 << 30;
        if (this->OwnRenders.value(view, 0) < wanted)
        {
          needsRender = true;
        }
        continue;
      }
      proxy->UpdatePropertyInformation();
      const int converged = vtkSMPropertyHelper(proxy, "Converged").GetAsInt();
      const int samples = vtkSMPropertyHelper(proxy, "TotalSamples").GetAsInt();
      const char* status = vtkSMPropertyHelper(proxy, "ChannelStatus").GetAsString();
      if (view == pqActiveObjects::instance().activeView() &&
        (statusLine.isEmpty() || repr == pqActiveObjects::instance().activeRepresentation()))
      {
        statusLine = progressLine(proxy, samples, converged, status);
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
    }
    if (needsRender)
    {
      if (remote)
      {
        this->Pending[view] = true;
      }
      view->forceRender();
      rendered = true;
    }
  }
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
