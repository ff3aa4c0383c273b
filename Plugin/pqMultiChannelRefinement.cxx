// SPDX-License-Identifier: BSD-3-Clause
#include "pqMultiChannelRefinement.h"

#include "pqApplicationCore.h"
#include "pqRenderView.h"
#include "pqRepresentation.h"
#include "pqServer.h"
#include "pqServerManagerModel.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"

#include <QApplication>

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
}

//------------------------------------------------------------------------------
void pqMultiChannelRefinement::shutdown()
{
  this->Timer.stop();
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
  // Nothing to do: look again a little later rather than spin.
  this->Timer.setInterval(rendered ? 0 : 100);
}
