// MeshLab adapter of the C1 surface plugin (thesis chapter 3): maps parameters, layers, progress and
// errors to the host-free core common/include/pectus/c1/surface.h. No algorithm lives here.
#pragma once
#include "filter_plugin.h"

class FilterC1SurfacePlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_C1_REFINE, FP_C1_PROJECT };
  FilterC1SurfacePlugin();
  QString pluginName() const override { return "FilterPectusC1Surface"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void runRefine(pectus::ml::FilterContext& ctx);
  void runProject(pectus::ml::FilterContext& ctx);
};
