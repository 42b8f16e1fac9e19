// MeshLab adapter of the quad conversion plugin (thesis 4.1): maps parameters, layers, progress and errors
// to the host-free cores in core/. No algorithm lives here.
#pragma once
#include "filter_plugin.h"

class FilterQuadConvertPlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_TRI_TO_QUAD, FP_STRUCTURE, FP_SAVE_POLY };
  FilterQuadConvertPlugin();
  QString pluginName() const override { return "FilterPectusQuadConvert"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void runConvert(pectus::ml::FilterContext& ctx);
  void runStructure(pectus::ml::FilterContext& ctx);
  void runSave(pectus::ml::FilterContext& ctx);
};
