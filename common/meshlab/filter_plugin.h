// The adapter contract every pectus-meshlab filter follows (written once, used by every plugin):
//  - applyFilter catches every exception; on failure it logs the reason and leaves every layer
//    exactly as it was (modified layers are restored from a snapshot, added layers are removed); then,
//    in MeshLab 2020.09, it sets errorMessage and returns false (meshlabserver prints only "Problem with
//    filter" on its own, hence the log line), and in 2021.05 and later it throws MLException, the one
//    exception MeshLab's GUI, pymeshlab and pectus-mlrun report as a filter failure;
//  - progress goes through MeshLab's callback;
//  - the figures a filter puts into ctx.results() (pectus/results.h) reach the host after a successful run:
//    in 2021.05 and later as applyFilter's return values (what pymeshlab's apply_filter returns; pectus-mlrun
//    writes them to $PECTUS_RESULTS_FILE); in 2020.09 as a JSON line appended to $PECTUS_RESULTS_FILE when it is
//    set, and one Log line "Results: key = value, ..."; on every host as a JSON file where the filter names
//    one (FilterContext::writeResultsTo). A failed run returns and writes none;
//  - a numeric parameter is declared once, with its valid range (addFloat, addInt): the tool-tip ends with
//    that range, and run() reads the value through a checked accessor that enforces the same range and
//    names the parameter and the range when the value lies outside.
// A plugin derives from FilterPluginBase (and QObject), declares PECTUS_FILTER_PLUGIN_METADATA after
// Q_OBJECT, registers FilterSpecs in its constructor, and implements initParameters() and run().
// The two MeshLab APIs differ only here and in ml_compat.h.
#pragma once
#include "ml_compat.h"

#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "pectus/param_range.h"
#include "pectus/results.h"

namespace pectus::ml {

using pectus::ParamRange;

/// A numeric parameter's declared range; integer: declared with addInt
struct DeclaredRange {
  ParamRange range;
  bool integer = false;
};
/// the declared ranges of one filter, by parameter name
using DeclaredRanges = std::map<QString, DeclaredRange>;

/// Declares a Float parameter whose valid values are `range`: the tool-tip shown to users is `tooltip`
/// followed by "Range: <range>.", and the range is recorded for FilterContext::floatIn(name) (while the
/// plugin base collects the declaration of a filter, i.e. inside initParameters).
void addFloat(RichParameterList& par, const QString& name, double def, const QString& label, const QString& tooltip,
              const ParamRange& range);
/// MeshLab's float field shows a value with 3 significant digits and applies what it shows: such a default
/// (12.25, 11500) is declared as a bounded float, whose field shows it as written.
bool floatFieldRoundsShownValue(double def);
/// The same for an Int parameter, read with FilterContext::intIn(name).
void addInt(RichParameterList& par, const QString& name, int def, const QString& label, const QString& tooltip,
            const ParamRange& range);
/// the tool-tip addFloat/addInt declare: `tooltip` and then the range
QString tooltipWithRange(const QString& tooltip, const ParamRange& range, bool integer);

struct FilterSpec {
  int id = 0;
  QString name;
  QString info;  ///< shown at the top of the GUI dialog: at most three lines
  /// the stem of the filter's page in docs/filters/ (linked under the info); empty: no link
  QString doc;
  /// parameters a user rarely changes (solver, tolerances, radii): behind "advanced" in MeshLab 2021.05 and
  /// later, which hide them until asked
  QStringList advanced;
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
  /// ranges: the filter's declared ranges (FilterPluginBase passes them), read by floatIn and intIn
  FilterContext(MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb,
                std::function<void(const std::string&)> logger, QString filterName,
                const DeclaredRanges* ranges = nullptr);
  ~FilterContext();

  MeshDocument& doc() { return md_; }
  const RichParameterList& params() const { return par_; }
  /// the current layer; throws InputError if there is none
  MeshModel& current();

  void log(const std::string& line) const;
  /// a line at the Log's debug level (solver histories: for those who look into a run, not its result)
  void debug(const std::string& line) const;
  void setDebugLogger(std::function<void(const std::string&)> logger) { debugLogger_ = std::move(logger); }
  /// The figures this run returns (force_N, elevation_mm, ...; keys in snake_case with the unit as suffix).
  /// The plugin base hands them to the host when the run succeeds, and drops them when it fails.
  pectus::Results& results() { return results_; }
  const pectus::Results& results() const { return results_; }
  /// After a successful run, also write the results as one JSON object (with the filter's name) to `path`,
  /// beside the filter's other outputs (e.g. "<output base>_results.json"); a file that cannot be written
  /// fails the run. Empty: none.
  void writeResultsTo(const std::string& path) { resultsPath_ = path; }
  const std::string& resultsPath() const { return resultsPath_; }
  const QString& filterName() const { return filterName_; }

  /// progress in percent [0,100] with a short label; safe to call with no callback
  void progress(int percent, const char* what) const;
  vcg::CallBackPos* callback() const { return cb_; }

  /// Announce that `m` is about to change: its mesh and data mask are snapshot once and restored
  /// if the filter fails. Call it after computing, right before writing results.
  CMeshO& modify(MeshModel& m);
  /// A new layer, removed again if the filter fails.
  MeshModel& addLayer(const QString& label, bool setCurrent = true);

  // Checked parameters, in the range declared with addFloat/addInt: a value outside throws
  // InputError("parameter 'X' must be in [lo, hi], got v"); a parameter declared without a range is a
  // programming error (std::logic_error).
  float floatIn(const QString& name) const;
  int intIn(const QString& name) const;
  /// A parameter declared with addFloat/addInt whose range the core checks itself, with the same range
  /// constant and messages of its own (e.g. with ranges that depend on other parameters): its value,
  /// unchecked here.
  float floatCheckedByCore(const QString& name) const;
  int intCheckedByCore(const QString& name) const;
  bool boolean(const QString& name) const { return par_.getBool(name); }
  int enumIn(const QString& name, int count) const;
  MeshModel& mesh(const QString& name) const;
  /// The landmark layer of the cage `cage` (its layers; empty: none known) by role, not by position
  /// (pectus/layer_roles.h): the layer the parameter `name` names when it is a point layer of landmark codes with
  /// the codes `needed` that lies on the cage, else the one such layer that does. Logs which layer it took when
  /// that is not the named one; throws InputError naming the layers and what to choose (ending with `hint`)
  /// when none or several fit. `exclude`: layers that cannot be it (the cage).
  MeshModel& landmarkLayer(const QString& name, const std::vector<const MeshModel*>& cage, const std::vector<int>& needed,
                           const std::string& hint, const std::vector<const MeshModel*>& exclude = {}) const;
  /// The before state of `measured` by role: the named layer when it is the same mesh (vertex count),
  /// else the layer `measured` was computed from (recordSource) when it is, else the one layer that is; logs and
  /// throws as landmarkLayer does.
  MeshModel& beforeLayer(const QString& name, const MeshModel& measured) const;
  QString string(const QString& name) const { return par_.getString(name); }

  void commit();
  void rollback();

 private:
  struct Snapshot;
  MeshDocument& md_;
  const RichParameterList& par_;
  vcg::CallBackPos* cb_;
  std::function<void(const std::string&)> logger_, debugLogger_;
  QString filterName_;
  const DeclaredRanges* ranges_;
  pectus::Results results_;
  std::string resultsPath_;
  const DeclaredRange& declared(const QString& name, bool integer) const;
  float checkedFloat(const QString& name, const ParamRange& r) const;
  int checkedInt(const QString& name, const ParamRange& r) const;
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
  /// Name of the QAction property that holds a filter's declared ranges once its parameters were declared:
  /// a QVariantMap from parameter name to the list {lo, hi, loOpen, hiOpen, integer} (for tools that load
  /// the plugin, such as pectus_layer_check --params).
  static constexpr const char* kRangesProperty = "pectusParameterRanges";

 protected:
  /// call from the derived constructor with `this` (MeshLab finds the plugin as the action's parent)
  void addFilter(QObject* owner, const FilterSpec& spec);
  virtual void initParameters(int id, const MeshDocument& md, RichParameterList& par) = 0;
  virtual void run(int id, FilterContext& ctx) = 0;
  const FilterSpec& spec(int id) const;

 private:
  std::vector<FilterSpec> specs_;
  std::map<int, DeclaredRanges> ranges_;
  /// the filters whose parameters were declared (their ranges_ entry is complete, possibly empty)
  std::set<int> declared_;
  /// initParameters(id, ...) with the ranges its addFloat/addInt calls declare recorded for filter id
  void declare(int id, const MeshDocument& md, RichParameterList& par);
  /// the outcome of a run: empty on success (the filter's figures in `results`), else the message (already
  /// logged; `results` empty)
  std::string runFilter(int id, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb,
                        pectus::Results& results);
};

/// The first layer whose label (without extension) ends in "landmarks" (labels.h), else the current one:
/// the default of every "Landmark layer" parameter.
MeshModel* defaultLandmarkLayer(const MeshDocument& md);

/// Records in `result` (a layer a filter computed from another, e.g. the FE result from its cage) which layer it
/// came from, for FilterContext::beforeLayer; kept while the document is open.
void recordSource(MeshModel& result, const MeshModel& source);
/// The layer recordSource named for `m`, or nullptr (none recorded, or that layer is gone).
MeshModel* recordedSource(const MeshDocument& md, const MeshModel& m);

/// The JSON line a filter's results take in a results file: {"filter": "<name>", "results": {...}}
std::string resultsJsonLine(const std::string& filter, const pectus::Results& results);
/// Appends `line` and a newline to `path`; throws pectus::IOError naming the file when it cannot.
void appendLine(const std::string& path, const std::string& line);
/// The results file scripts read ($PECTUS_RESULTS_FILE), or "" when not set.
std::string resultsFileFromEnvironment();
#if PECTUS_MESHLAB_API >= 2021
/// The results as MeshLab's return values (what pymeshlab converts to a dict): a number as double, a count as
/// int (a double beyond int's range), a text as QString, a place as Point3m.
std::map<std::string, QVariant> toVariantMap(const pectus::Results& results);
/// The converse, for a runner that gets a filter's return values (any filter's: bool as a count 0/1, float as
/// a number, Point3m as a place; a type with none of these is skipped).
pectus::Results fromVariantMap(const std::map<std::string, QVariant>& values);
#endif

/// "a b c" for a histogram, for Log lines
std::string formatHistogram(const std::vector<std::size_t>& h);
/// a number for Log lines with `precision` decimals (pectus::fixedText)
std::string fmt(double v, int precision = 4);
/// a number for tool-tips, with at most 6 significant digits (pectus::significantText)
QString num(double v);

}  // namespace pectus::ml
