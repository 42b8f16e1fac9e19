// The adapter contract every pectus-meshlab filter follows (written once, used by every plugin):
//  - applyFilter catches every exception; on failure it logs the reason and leaves every layer
//    exactly as it was (modified layers are restored from a snapshot, added layers are removed); then,
//    in MeshLab 2020.09, it sets errorMessage and returns false (meshlabserver prints only "Problem with
//    filter" on its own, hence the log line), and in 2021.05 and later it throws MLException, the one
//    exception MeshLab's GUI, pymeshlab and pectus-mlrun report as a filter failure;
//  - progress goes through MeshLab's callback;
//  - parameters are read through checked accessors that name the parameter and its valid range.
// A plugin derives from FilterPluginBase (and QObject), declares PECTUS_FILTER_PLUGIN_METADATA after
// Q_OBJECT, registers FilterSpecs in its constructor, and implements initParameters() and run().
// The two MeshLab APIs differ only here and in ml_compat.h.
#pragma once
#include "ml_compat.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace pectus::ml {

struct FilterSpec {
  int id = 0;
  QString name;
  QString info;  ///< shown as the filter's help in the GUI dialog
  /// the function name in pymeshlab (MeshSet.<pythonName>(...)); empty: MeshLab's default, the name
  /// lower-cased with every other character as '_'
  QString pythonName;
  FilterClass cls = HostFilter::Measure;
  FilterArity arity = HostFilter::SINGLE_MESH;
  int requirements = MeshModel::MM_NONE;
  int postCondition = MeshModel::MM_NONE;
  bool needsCurrentMesh = true;  ///< refuse to run with no current layer
};

class FilterContext {
 public:
  FilterContext(MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb,
                std::function<void(const std::string&)> logger, QString filterName);
  ~FilterContext();

  MeshDocument& doc() { return md_; }
  const RichParameterList& params() const { return par_; }
  /// the current layer; throws InputError if there is none
  MeshModel& current();

  void log(const std::string& line) const;
  /// progress in percent [0,100] with a short label; safe to call with no callback
  void progress(int percent, const char* what) const;
  vcg::CallBackPos* callback() const { return cb_; }

  /// Announce that `m` is about to change: its mesh and data mask are snapshot once and restored
  /// if the filter fails. Call it after computing, right before writing results.
  CMeshO& modify(MeshModel& m);
  /// A new layer, removed again if the filter fails.
  MeshModel& addLayer(const QString& label, bool setCurrent = true);

  // Checked parameters: throw InputError("parameter 'X' (...) must be ..., got ...")
  float floatIn(const QString& name, double lo, double hi, bool loOpen = false, bool hiOpen = false) const;
  int intIn(const QString& name, int lo, int hi) const;
  bool boolean(const QString& name) const { return par_.getBool(name); }
  int enumIn(const QString& name, int count) const;
  MeshModel& mesh(const QString& name) const;
  QString string(const QString& name) const { return par_.getString(name); }

  void commit();
  void rollback();

 private:
  struct Snapshot;
  MeshDocument& md_;
  const RichParameterList& par_;
  vcg::CallBackPos* cb_;
  std::function<void(const std::string&)> logger_;
  QString filterName_;
  std::vector<std::unique_ptr<Snapshot>> snapshots_;
  std::vector<MeshModel*> added_;
  MeshModel* previousCurrent_ = nullptr;
  bool done_ = false;
};

class FilterPluginBase : public HostFilter {
 public:
  ~FilterPluginBase() override;
  QString filterName(int id) const override;
  QString filterInfo(int id) const override;
  FilterArity filterArity(ActionPtr a) const override;
  int getRequirements(ActionPtr a) override;
  int postCondition(ActionPtr a) const override;
#if PECTUS_MESHLAB_API >= 2021
  FilterClass getClass(const QAction* a) const override;
  using FilterPlugin::filterInfo;
  using FilterPlugin::filterName;
  using FilterPlugin::pythonFilterName;
  QString pythonFilterName(int id) const override;
  RichParameterList initParameterList(const QAction* a, const MeshDocument& md) override;
  std::map<std::string, QVariant> applyFilter(const QAction* a, const RichParameterList& par, MeshDocument& md,
                                              unsigned int& postConditionMask, vcg::CallBackPos* cb) final;
#else
  FilterClass getClass(QAction* a) override;
  void initParameterSet(QAction* a, MeshModel& m, RichParameterList& par) override;
  void initParameterSet(QAction* a, MeshDocument& md, RichParameterList& par) override;
  bool applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb) final;
#endif
  /// the pymeshlab name of a filter (also on 2020.09, for the docs and tests)
  QString pythonName(int id) const;

 protected:
  /// call from the derived constructor with `this` (MeshLab finds the plugin as the action's parent)
  void addFilter(QObject* owner, const FilterSpec& spec);
  virtual void initParameters(int id, const MeshDocument& md, RichParameterList& par) = 0;
  virtual void run(int id, FilterContext& ctx) = 0;
  const FilterSpec& spec(int id) const;

 private:
  std::vector<FilterSpec> specs_;
  /// the outcome of a run: empty on success, else the message (already logged)
  std::string runFilter(int id, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb);
};

/// The first layer whose label (without extension) ends in "landmarks" (labels.h), else the current one:
/// the default of every "Landmark layer" parameter.
MeshModel* defaultLandmarkLayer(const MeshDocument& md);

/// "a b c" for a histogram, and a fixed-format number, for Log lines
std::string formatHistogram(const std::vector<std::size_t>& h);
std::string fmt(double v, int precision = 4);

}  // namespace pectus::ml
