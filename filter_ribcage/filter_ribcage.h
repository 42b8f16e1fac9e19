// MeshLab adapter of the rib cage generator: maps parameters, layers, progress, errors and results to the
// host-free core in core/ (pectus/ribcage). No algorithm here.
#pragma once
#include "filter_plugin.h"

class FilterRibCagePlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_CREATE_RIBCAGE };
  FilterRibCagePlugin();
  QString pluginName() const override { return "FilterPectusRibCage"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void initCreateRibCage(RichParameterList& par);
  void runCreateRibCage(pectus::ml::FilterContext& ctx);
};
