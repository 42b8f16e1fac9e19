// MeshLab adapter of the Nuss FE analysis plugin: maps parameters, layers, progress and errors to the
// host-free cores (core/: the parametric rib cage; fe/: the finite element analysis; patient/: CT segmentation
// import). No algorithm here.
#pragma once
#include "filter_plugin.h"

class FilterNussFeaPlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_CREATE_RIBCAGE, FP_NUSS_FEA, FP_BAR_PLANNER, FP_IMPORT_CT, FP_PREPARE_PATIENT };
  FilterNussFeaPlugin();
  QString pluginName() const override { return "FilterPectusNussFea"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void initCreateRibCage(RichParameterList& par);
  void runCreateRibCage(pectus::ml::FilterContext& ctx);
  void initNussFea(const MeshDocument& md, RichParameterList& par);
  void runNussFea(pectus::ml::FilterContext& ctx);
  void initBarPlanner(const MeshDocument& md, RichParameterList& par);
  void runBarPlanner(pectus::ml::FilterContext& ctx);
  // a patient's CT segmentation (filter_patient.cpp)
  void addPatientFilters();
  void initImportCt(RichParameterList& par);
  void runImportCt(pectus::ml::FilterContext& ctx);
  void initPreparePatient(RichParameterList& par);
  void runPreparePatient(pectus::ml::FilterContext& ctx);
};
