// MeshLab adapter of the Nuss FE analysis and the Nuss bar planner: maps parameters, layers, progress, errors
// and results to the host-free core in core/ (pectus/nuss) and the FE library pectus_fe. No algorithm here.
#pragma once
#include "filter_plugin.h"

class FilterNussFeaPlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_NUSS_FEA, FP_BAR_PLANNER };
  FilterNussFeaPlugin();
  QString pluginName() const override { return "FilterPectusNussFea"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void initNussFea(const MeshDocument& md, RichParameterList& par);
  void runNussFea(pectus::ml::FilterContext& ctx);
  void initBarPlanner(const MeshDocument& md, RichParameterList& par);
  void runBarPlanner(pectus::ml::FilterContext& ctx);
};
