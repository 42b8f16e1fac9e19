// MeshLab adapter of the MGA smoothing plugin: maps parameters, layers, progress and errors to the
// host-free cores (common/ and this folder's core files). No algorithm lives here.
#pragma once
#include "filter_plugin.h"

class FilterMgaSmoothPlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_ELEMENT_QUALITY, FP_MGA_SMOOTH, FP_GRADIENT_SMOOTH };
  FilterMgaSmoothPlugin();
  QString pluginName() const override { return "FilterPectusMgaSmooth"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void runElementQuality(pectus::ml::FilterContext& ctx);
  /// both smoothing filters: MGA (thesis 4.2) and the conjugate gradient baseline (Table 4-1)
  void runSmooth(pectus::ml::FilterContext& ctx, bool mga);
};
