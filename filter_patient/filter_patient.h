// MeshLab adapter of a patient's CT segmentation: 'Pectus: Import CT Segmentation' and 'Pectus: Prepare Patient Rib Cage'.
// Maps parameters, layers, progress, errors and results to the host-free core in core/ (pectus/patient).
#pragma once
#include "filter_plugin.h"

class FilterPatientPlugin : public QObject, public pectus::ml::FilterPluginBase {
  Q_OBJECT
  PECTUS_FILTER_PLUGIN_METADATA

 public:
  enum { FP_IMPORT_CT, FP_PREPARE_PATIENT };
  FilterPatientPlugin();
  QString pluginName() const override { return "FilterPectusPatient"; }

 protected:
  void initParameters(int id, const MeshDocument& md, RichParameterList& par) override;
  void run(int id, pectus::ml::FilterContext& ctx) override;

 private:
  void initImportCt(RichParameterList& par);
  void runImportCt(pectus::ml::FilterContext& ctx);
  void initPreparePatient(RichParameterList& par);
  void runPreparePatient(pectus::ml::FilterContext& ctx);
};
