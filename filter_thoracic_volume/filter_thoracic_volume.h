// MeshLab adapter of the thoracic volume plugin (thesis 6.3, 6.4.2): maps parameters, layers,
// progress and errors to the host-free cores in core/. No algorithm lives here.
#pragma once
#include "filter_plugin.h"
#include "pectus/surface.h"

namespace pectus::vol {
using Soup = pectus::Surface;
struct Range;
}  // namespace pectus::vol

class FilterThoracicVolumePlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_SLICE_VOLUME, FP_ENVELOPE_VOLUME, FP_PECTUS_INDEX };
  FilterThoracicVolumePlugin();
  QString pluginName() const override { return "FilterPectusThoracicVolume"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void runSlice(pectus::ml::FilterContext& ctx);
  void runEnvelope(pectus::ml::FilterContext& ctx);
  void runIndex(pectus::ml::FilterContext& ctx);
};
