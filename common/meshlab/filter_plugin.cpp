#include "filter_plugin.h"

#include <QVariant>
#include <vcg/complex/append.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/format.h"
#include "pectus/layer_roles.h"

namespace pectus::ml {

// ---------------------------------------------------------------------------------------------
// snapshots

namespace {
void enableLike(CMeshO& dst, const CMeshO& src) {
  if (src.vert.IsVFAdjacencyEnabled()) dst.vert.EnableVFAdjacency();
  if (src.vert.IsMarkEnabled()) dst.vert.EnableMark();
  if (src.vert.IsTexCoordEnabled()) dst.vert.EnableTexCoord();
  if (src.vert.IsCurvatureEnabled()) dst.vert.EnableCurvature();
  if (src.vert.IsCurvatureDirEnabled()) dst.vert.EnableCurvatureDir();
  if (src.vert.IsRadiusEnabled()) dst.vert.EnableRadius();
  if (src.face.IsQualityEnabled()) dst.face.EnableQuality();
  if (src.face.IsColorEnabled()) dst.face.EnableColor();
  if (src.face.IsMarkEnabled()) dst.face.EnableMark();
  if (src.face.IsFFAdjacencyEnabled()) dst.face.EnableFFAdjacency();
  if (src.face.IsVFAdjacencyEnabled()) dst.face.EnableVFAdjacency();
  if (src.face.IsCurvatureDirEnabled()) dst.face.EnableCurvatureDir();
  if (src.face.IsWedgeTexCoordEnabled()) dst.face.EnableWedgeTexCoord();
}

// Named per-vertex/per-face custom attributes (vcg's AddPerFaceAttribute, e.g. tissue labels) are
// not copied by MeshCopy into a mesh that lacks them: keep their raw bytes beside the copy.
struct AttributeBytes {
  std::string name;
  std::size_t count = 0;
  std::vector<char> bytes;
};

std::vector<AttributeBytes> saveAttributes(const std::set<vcg::PointerToAttribute>& attrs, std::size_t count) {
  std::vector<AttributeBytes> out;
  for (const auto& a : attrs) {
    if (a._name.empty()) continue;
    auto* h = static_cast<vcg::SimpleTempDataBase*>(a._handle);
    AttributeBytes b{a._name, count, {}};
    b.bytes.resize(h->SizeOf() * count);
    if (count) std::memcpy(b.bytes.data(), h->DataBegin(), b.bytes.size());
    out.push_back(std::move(b));
  }
  return out;
}

void restoreAttributes(std::set<vcg::PointerToAttribute>& attrs, const std::vector<AttributeBytes>& saved) {
  for (auto it = attrs.begin(); it != attrs.end();) {
    const AttributeBytes* b = nullptr;
    for (const auto& s : saved)
      if (s.name == it->_name) b = &s;
    auto* h = static_cast<vcg::SimpleTempDataBase*>(it->_handle);
    if (b == nullptr) {  // added by the failed filter (or unnamed): drop it
      if (!it->_name.empty()) {
        delete h;
        it = attrs.erase(it);
        continue;
      }
    } else {
      h->Resize(b->count);
      if (b->count) std::memcpy(h->DataBegin(), b->bytes.data(), b->bytes.size());
    }
    ++it;
  }
}
}  // namespace

struct FilterContext::Snapshot {
  MeshModel* model = nullptr;
  int dataMask = 0;
  CMeshO copy;
  std::vector<AttributeBytes> vertAttr, faceAttr;
};

FilterContext::FilterContext(MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb,
                             std::function<void(const std::string&)> logger, QString filterName,
                             const DeclaredRanges* ranges)
    : md_(md), par_(par), cb_(cb), logger_(std::move(logger)), filterName_(std::move(filterName)), ranges_(ranges),
      previousCurrent_(md.mm()) {}

FilterContext::~FilterContext() {
  if (!done_) rollback();
}

MeshModel& FilterContext::current() {
  if (md_.mm() == nullptr) throw InputError("there is no current layer: load or create a mesh first");
  return *md_.mm();
}

void FilterContext::log(const std::string& line) const {
  if (logger_) logger_(line);
}

void FilterContext::debug(const std::string& line) const {
  if (debugLogger_) debugLogger_(line);
}

void FilterContext::progress(int percent, const char* what) const {
  if (cb_) cb_(std::max(0, std::min(100, percent)), what);
}

CMeshO& FilterContext::modify(MeshModel& m) {
  for (const auto& s : snapshots_)
    if (s->model == &m) return m.cm;
  for (MeshModel* a : added_)
    if (a == &m) return m.cm;  // a layer of our own: removed on failure anyway
  auto s = std::make_unique<Snapshot>();
  s->model = &m;
  s->dataMask = m.dataMask();
  enableLike(s->copy, m.cm);
  vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(s->copy, m.cm, false, false);
  s->copy.Tr = m.cm.Tr;
  s->copy.bbox = m.cm.bbox;
  s->vertAttr = saveAttributes(m.cm.vert_attr, m.cm.vert.size());
  s->faceAttr = saveAttributes(m.cm.face_attr, m.cm.face.size());
  snapshots_.push_back(std::move(s));
  return m.cm;
}

MeshModel& FilterContext::addLayer(const QString& label, bool setCurrent) {
  MeshModel* mm = md_.addNewMesh("", label, setCurrent);
  if (mm == nullptr) throw std::runtime_error("MeshLab could not add a layer");
  added_.push_back(mm);
  return *mm;
}

void FilterContext::commit() { done_ = true; }

void FilterContext::rollback() {
  done_ = true;
  for (auto it = added_.rbegin(); it != added_.rend(); ++it) removeLayer(md_, *it);
  added_.clear();
  for (auto& s : snapshots_) {
    MeshModel& m = *s->model;
    const int now = m.dataMask();
    m.clearDataMask(now & ~s->dataMask);
    m.updateDataMask(s->dataMask);
    m.cm.Clear();
    vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(m.cm, s->copy, false, false);
    m.cm.Tr = s->copy.Tr;
    m.cm.bbox = s->copy.bbox;
    restoreAttributes(m.cm.vert_attr, s->vertAttr);
    restoreAttributes(m.cm.face_attr, s->faceAttr);
    if (m.cm.face.IsFFAdjacencyEnabled()) vcg::tri::UpdateTopology<CMeshO>::FaceFace(m.cm);
    if (m.cm.vert.IsVFAdjacencyEnabled() && m.cm.face.IsVFAdjacencyEnabled())
      vcg::tri::UpdateTopology<CMeshO>::VertexFace(m.cm);
  }
  snapshots_.clear();
  if (previousCurrent_ != nullptr) md_.setCurrentMesh(previousCurrent_->id());
}

// ---------------------------------------------------------------------------------------------
// checked parameters

namespace {
std::string q(const QString& s) { return s.toStdString(); }
}  // namespace

const DeclaredRange& FilterContext::declared(const QString& name, bool integer) const {
  const auto it = ranges_ ? ranges_->find(name) : DeclaredRanges::const_iterator();
  if (ranges_ == nullptr || it == ranges_->end() || it->second.integer != integer)
    throw std::logic_error("parameter '" + q(name) + "' has no range declared with " + (integer ? "addInt" : "addFloat"));
  return it->second;
}

float FilterContext::floatIn(const QString& name) const { return checkedFloat(name, declared(name, false).range); }
int FilterContext::intIn(const QString& name) const { return checkedInt(name, declared(name, true).range); }

float FilterContext::floatCheckedByCore(const QString& name) const {
  declared(name, false);
  return par_.getFloat(name);
}

int FilterContext::intCheckedByCore(const QString& name) const {
  declared(name, true);
  return par_.getInt(name);
}

float FilterContext::checkedFloat(const QString& name, const ParamRange& r) const {
  const double v = par_.getFloat(name);
  if (!r.contains(v)) {
    std::ostringstream s;
    s << "parameter '" << q(name) << "' must be in " << r.text() << ", got " << v;
    throw InputError(s.str());
  }
  return float(v);
}

int FilterContext::checkedInt(const QString& name, const ParamRange& r) const {
  const int v = par_.getInt(name);
  if (!r.contains(v))
    throw InputError("parameter '" + q(name) + "' must be an integer in " + r.text(true) + ", got " + std::to_string(v));
  return v;
}

int FilterContext::enumIn(const QString& name, int count) const {
  const int v = par_.getEnum(name);
  if (v < 0 || v >= count)
    throw InputError("parameter '" + q(name) + "' must be one of 0.." + std::to_string(count - 1) + ", got " +
                     std::to_string(v));
  return v;
}

MeshModel& FilterContext::mesh(const QString& name) const {
  MeshModel* m = meshParam(par_, md_, name);
  if (m == nullptr) throw InputError("parameter '" + q(name) + "' does not name an existing layer");
  return *m;
}

// ---------------------------------------------------------------------------------------------
// layer parameters by role (pectus/layer_roles.h)

namespace {
constexpr const char* kSourceAttr = "pectus_source_layer";

/// the document's layers as the role checks see them, and the index of each of `wanted` (-1: not there)
std::vector<LayerRef> layerRefs(const MeshDocument& md, std::vector<MeshModel*>& models) {
  models = meshes(md);
  std::vector<LayerRef> refs;
  for (MeshModel* m : models) refs.push_back({q(m->label()), &m->cm, layerNumber(md, *m)});
  return refs;
}
int indexOf(const std::vector<MeshModel*>& models, const MeshModel* m) {
  const auto it = std::find(models.begin(), models.end(), m);
  return it == models.end() ? -1 : int(it - models.begin());
}
void logChoice(const FilterContext& ctx, const char* role, const LayerRef& chosen, const std::string& note) {
  if (!note.empty()) ctx.log(std::string(role) + ": '" + chosen.label + "', layer " + std::to_string(chosen.number) + " (" + note + ")");
}
}  // namespace

MeshModel& FilterContext::landmarkLayer(const QString& name, const std::vector<const MeshModel*>& cage,
                                        const std::vector<int>& needed, const std::string& hint,
                                        const std::vector<const MeshModel*>& exclude) const {
  std::vector<MeshModel*> models;
  const auto refs = layerRefs(md_, models);
  std::vector<const CMeshO*> surfaces;
  for (const MeshModel* m : cage) surfaces.push_back(&m->cm);
  std::vector<int> out;
  for (const MeshModel* m : exclude) out.push_back(indexOf(models, m));
  const auto c = chooseLandmarkLayer(refs, indexOf(models, meshParam(par_, md_, name)), out, surfaces, needed, q(name), hint);
  logChoice(*this, "landmark layer", refs[std::size_t(c.index)], c.note);
  return *models[std::size_t(c.index)];
}

MeshModel& FilterContext::beforeLayer(const QString& name, const MeshModel& measured) const {
  std::vector<MeshModel*> models;
  const auto refs = layerRefs(md_, models);
  const auto c = chooseBeforeLayer(refs, indexOf(models, meshParam(par_, md_, name)), indexOf(models, &measured),
                                   indexOf(models, recordedSource(md_, measured)), q(name));
  logChoice(*this, "before layer", refs[std::size_t(c.index)], c.note);
  return *models[std::size_t(c.index)];
}

void recordSource(MeshModel& result, const MeshModel& source) {
  auto h = vcg::tri::Allocator<CMeshO>::GetPerMeshAttribute<int>(result.cm, kSourceAttr);
  h() = int(source.id());
}

MeshModel* recordedSource(const MeshDocument& md, const MeshModel& m) {
  auto h = vcg::tri::Allocator<CMeshO>::FindPerMeshAttribute<int>(const_cast<CMeshO&>(m.cm), kSourceAttr);
  if (h._handle == nullptr) return nullptr;
  for (MeshModel* other : meshes(md))
    if (other != &m && int(other->id()) == h()) return other;
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// declared parameters

namespace {
// the ranges of the filter whose parameters are being declared (FilterPluginBase::declare), else nullptr
thread_local DeclaredRanges* tDeclaring = nullptr;

void record(const QString& name, const ParamRange& range, bool integer) {
  if (!(range.lo <= range.hi)) throw std::logic_error("parameter '" + q(name) + "': empty range " + range.text(integer));
  if (tDeclaring != nullptr) (*tDeclaring)[name] = DeclaredRange{range, integer};
}
}  // namespace

QString tooltipWithRange(const QString& tooltip, const ParamRange& range, bool integer) {
  const QString t = tooltip.trimmed();
  return t + (t.isEmpty() ? "" : " ") + "Range: " + QString::fromStdString(range.text(integer)) + ".";
}

bool floatFieldRoundsShownValue(double def) { return QString::number(def, 'g', 3) != QString::number(def, 'g', 7); }

void addFloat(RichParameterList& par, const QString& name, double def, const QString& label, const QString& tooltip,
              const ParamRange& range) {
  record(name, range, false);
  const QString tip = tooltipWithRange(tooltip, range, false);
  // MeshLab's float field shows 3 significant digits and applies what it shows (12.25 would become 12.3);
  // its bounded-float field shows the value as written
  if (floatFieldRoundsShownValue(def))
    par.addParam(RichDynamicFloat(name, float(def), float(range.lo), float(range.hi), label, tip));
  else
    par.addParam(RichFloat(name, float(def), label, tip));
}

void addInt(RichParameterList& par, const QString& name, int def, const QString& label, const QString& tooltip,
            const ParamRange& range) {
  record(name, range, true);
  par.addParam(RichInt(name, def, label, tooltipWithRange(tooltip, range, true)));
}

// ---------------------------------------------------------------------------------------------
// plugin base

FilterPluginBase::~FilterPluginBase() {
  for (QAction* a : actionList) delete a;
}

void FilterPluginBase::addFilter(QObject* owner, const FilterSpec& spec) {
  specs_.push_back(spec);
  typeList.push_back(spec.id);
  actionList.push_back(new QAction(spec.name, owner));
}

const FilterSpec& FilterPluginBase::spec(int id) const {
  for (const auto& s : specs_)
    if (s.id == id) return s;
  static const FilterSpec none;
  return none;
}

namespace {
#if PECTUS_MESHLAB_API >= 2021
// RichParameter sets its protected 'advanced' flag only in its constructor; a derived class may name the
// member, which lets the flag be set on a parameter already declared
struct AdvancedFlag : RichParameter {
  static bool RichParameter::*member() { return &AdvancedFlag::advanced; }
};
#endif

// the parameters a filter lists as advanced: hidden until asked where MeshLab can (2021.05 and later)
void markAdvanced(const FilterSpec& s, RichParameterList& par) {
  for (const QString& name : s.advanced) {
    if (!par.hasParameter(name))
      throw std::logic_error("filter '" + q(s.name) + "' lists '" + q(name) + "' as advanced but declares no such parameter");
#if PECTUS_MESHLAB_API >= 2021
    par.getParameterByName(name).*AdvancedFlag::member() = true;
#endif
  }
}
}  // namespace

void FilterPluginBase::declare(int id, const MeshDocument& md, RichParameterList& par) {
  DeclaredRanges ranges;
  struct Restore {
    DeclaredRanges* previous;
    ~Restore() { tDeclaring = previous; }
  } restore{tDeclaring};
  tDeclaring = &ranges;
  initParameters(id, md, par);
  markAdvanced(spec(id), par);
  QVariantMap published;
  for (const auto& [name, d] : ranges)
    published[name] = QVariantList{d.range.lo, d.range.hi, d.range.loOpen, d.range.hiOpen, d.integer};
  for (std::size_t i = 0; i < specs_.size(); ++i)
    if (specs_[i].id == id) (*std::next(actionList.begin(), long(i)))->setProperty(kRangesProperty, published);
  ranges_[id] = std::move(ranges);
  declared_.insert(id);
}

QString FilterPluginBase::filterName(int id) const { return spec(id).name; }
QString FilterPluginBase::filterInfo(int id) const {
  const FilterSpec& s = spec(id);
  if (s.doc.isEmpty()) return s.info;
  const QString page = QStringLiteral(PECTUS_DOC_DIR "/filters/") + s.doc + ".md";
  return s.info + "<br>Details: <a href=\"file://" + page + "\">" + s.doc + ".md</a>";
}
FilterArity FilterPluginBase::filterArity(ActionPtr a) const { return spec(ID(a)).arity; }
int FilterPluginBase::getRequirements(ActionPtr a) { return spec(ID(a)).requirements; }
int FilterPluginBase::postCondition(ActionPtr a) const { return spec(ID(a)).postCondition; }

QString FilterPluginBase::pythonName(int id) const {
  const FilterSpec& s = spec(id);
  if (!s.pythonName.isEmpty()) return s.pythonName;
  // MeshLab's default (FilterPlugin::pythonFilterName): lower case, every other character as '_'
  QString n = s.name.toLower();
  for (QChar& c : n)
    if (!c.isLetterOrNumber()) c = '_';
  return n;
}

// Runs filter `id`; on success `results` holds its figures, written where the run asks (FilterContext::
// writeResultsTo) and, on 2020.09, to $PECTUS_RESULTS_FILE and the Log; on failure rolls every layer back and
// returns the logged message.
std::string FilterPluginBase::runFilter(int id, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb,
                                        pectus::Results& results) {
  const QString name = filterName(id);
#if PECTUS_MESHLAB_API >= 2021
  auto logger = [this](const std::string& s) { log(GLLogStream::FILTER, s); };
  auto debugLogger = [this](const std::string& s) { log(GLLogStream::DEBUG, s); };
#else
  auto logger = [this](const std::string& s) { Log(GLLogStream::FILTER, s.c_str()); };
  auto debugLogger = [this](const std::string& s) { Log(GLLogStream::DEBUG, s.c_str()); };
#endif
  results.clear();
  std::string failure;
  {
    FilterContext ctx(md, par, cb, logger, name, &ranges_[id]);
    ctx.setDebugLogger(debugLogger);
    try {
      if (!declared_.count(id)) {  // the host may run a script without asking for the parameters first
        RichParameterList declared;
        declare(id, md, declared);
      }
      if (spec(id).needsCurrentMesh) ctx.current();
      run(id, ctx);
      const std::string line = resultsJsonLine(name.toStdString(), ctx.results());
      if (!ctx.resultsPath().empty()) {
        std::ofstream f(ctx.resultsPath(), std::ios::binary | std::ios::trunc);
        f << line << "\n";
        f.close();
        if (!f) throw IOError("cannot write the results file " + ctx.resultsPath());
      }
#if PECTUS_MESHLAB_API < 2021
      // 2020.09 has no return values: the results file scripts read, and the Log (pectus-mlrun writes the
      // file from the return values on the newer hosts)
      const std::string file = resultsFileFromEnvironment();
      if (!file.empty()) appendLine(file, line);
      if (!ctx.results().empty()) ctx.log("Results: " + ctx.results().toText());
#endif
      ctx.commit();
      results = std::move(ctx.results());
      ctx.progress(100, "done");
      return {};
    } catch (const InputError& e) {  // and its kinds TopologyError, SolverFailure, IOError (pectus/errors.h)
      failure = e.what();
    } catch (const std::bad_alloc&) {
      failure = "out of memory";
    } catch (const std::exception& e) {  // pectus::InternalError too
      failure = std::string("internal error: ") + e.what();
    } catch (...) {
      failure = "unknown internal error";
    }
    ctx.rollback();
  }
  results.clear();
  const std::string msg = name.toStdString() + " failed: " + failure + " (the layers are unchanged)";
#if PECTUS_MESHLAB_API >= 2021
  log(GLLogStream::WARNING, msg);
#else
  Log(GLLogStream::WARNING, msg.c_str());
#endif
  return msg;
}

#if PECTUS_MESHLAB_API >= 2021

FilterClass FilterPluginBase::getClass(const QAction* a) const { return spec(ID(a)).cls; }
QString FilterPluginBase::pythonFilterName(int id) const { return pythonName(id); }

RichParameterList FilterPluginBase::initParameterList(const QAction* a, const MeshDocument& md) {
  RichParameterList par;
  try {
    declare(ID(a), md, par);
  } catch (const std::exception& e) {
    log(GLLogStream::WARNING, (filterName(ID(a)) + ": " + e.what()).toStdString());
  }
  return par;
}

std::map<std::string, QVariant> FilterPluginBase::applyFilter(const QAction* a, const RichParameterList& par,
                                                              MeshDocument& md, unsigned int&,
                                                              vcg::CallBackPos* cb) {
  pectus::Results results;
  const std::string failure = runFilter(ID(a), md, par, cb, results);
  if (!failure.empty()) throw MLException(QString::fromStdString(failure));
  return toVariantMap(results);
}

#else

FilterClass FilterPluginBase::getClass(QAction* a) { return spec(ID(a)).cls; }

void FilterPluginBase::initParameterSet(QAction* a, MeshModel&, RichParameterList&) { (void)a; }

void FilterPluginBase::initParameterSet(QAction* a, MeshDocument& md, RichParameterList& par) {
  try {
    declare(ID(a), md, par);
  } catch (const std::exception& e) {
    Log(GLLogStream::WARNING, (filterName(ID(a)) + ": " + e.what()).toUtf8().constData());
  }
}

bool FilterPluginBase::applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb) {
  pectus::Results results;
  const std::string failure = runFilter(ID(a), md, par, cb, results);
  if (failure.empty()) return true;
  errorMessage = QString::fromStdString(failure);
  return false;
}

#endif

// ---------------------------------------------------------------------------------------------
// the document, across both APIs

#if PECTUS_MESHLAB_API >= 2021
const char* hostVersion() { return meshlab_xstr(MESHLAB_VERSION); }

std::vector<MeshModel*> meshes(const MeshDocument& md) {
  std::vector<MeshModel*> out;
  for (const MeshModel& m : md.meshIterator()) out.push_back(const_cast<MeshModel*>(&m));
  return out;
}
MeshModel* currentMesh(const MeshDocument& md) { return const_cast<MeshModel*>(md.mm()); }
void removeLayer(MeshDocument& md, MeshModel* m) { md.delMesh(m->id()); }
RichMesh richMesh(const QString& name, MeshModel* def, const MeshDocument& md, const QString& desc,
                  const QString& help) {
  if (def == nullptr && md.meshNumber() > 0) def = meshes(md).front();
  return RichMesh(name, def ? unsigned(def->id()) : 0u, &md, desc, help);
}
MeshModel* meshParam(const RichParameterList& par, MeshDocument& md, const QString& name) {
  return md.getMesh(par.getMeshId(name));
}
int layerNumber(const MeshDocument&, const MeshModel& m) { return int(m.id()); }
void updateBoxAndNormals(MeshModel& m) { m.updateBoxAndNormals(); }
#else
const char* hostVersion() { return "2020.09"; }

std::vector<MeshModel*> meshes(const MeshDocument& md) {
  return std::vector<MeshModel*>(md.meshList.begin(), md.meshList.end());
}
MeshModel* currentMesh(const MeshDocument& md) { return const_cast<MeshDocument&>(md).mm(); }
void removeLayer(MeshDocument& md, MeshModel* m) { md.delMesh(m); }
RichMesh richMesh(const QString& name, MeshModel* def, const MeshDocument& md, const QString& desc,
                  const QString& help) {
  return RichMesh(name, def, &const_cast<MeshDocument&>(md), desc, help);
}
MeshModel* meshParam(const RichParameterList& par, MeshDocument&, const QString& name) { return par.getMesh(name); }
int layerNumber(const MeshDocument& md, const MeshModel& m) { return int(md.meshList.indexOf(const_cast<MeshModel*>(&m))); }
void updateBoxAndNormals(MeshModel& m) { m.UpdateBoxAndNormals(); }
#endif

// ---------------------------------------------------------------------------------------------
// results

std::string resultsJsonLine(const std::string& filter, const pectus::Results& results) {
  return "{\"filter\": " + pectus::Results::jsonString(filter) + ", \"results\": " + results.toJson() + "}";
}

void appendLine(const std::string& path, const std::string& line) {
  std::ofstream f(path, std::ios::binary | std::ios::app);
  f << line << "\n";
  f.close();
  if (!f) throw IOError("cannot append to the results file " + path + " ($PECTUS_RESULTS_FILE)");
}

std::string resultsFileFromEnvironment() {
  const char* p = std::getenv("PECTUS_RESULTS_FILE");
  return p ? std::string(p) : std::string();
}

#if PECTUS_MESHLAB_API >= 2021
std::map<std::string, QVariant> toVariantMap(const pectus::Results& results) {
  std::map<std::string, QVariant> out;
  for (const auto& e : results.entries()) {
    QVariant v;
    if (const auto* d = std::get_if<double>(&e.value)) {
      v = QVariant(*d);
    } else if (const auto* i = std::get_if<long long>(&e.value)) {
      // pymeshlab converts int, double, float, bool and vcg's types, not qlonglong
      if (*i >= std::numeric_limits<int>::min() && *i <= std::numeric_limits<int>::max()) v = QVariant(int(*i));
      else v = QVariant(double(*i));
    } else if (const auto* s = std::get_if<std::string>(&e.value)) {
      v = QVariant(QString::fromStdString(*s));
    } else {
      const auto& p = std::get<pectus::Results::Vec3>(e.value);
      v = QVariant::fromValue(Point3m(Scalarm(p[0]), Scalarm(p[1]), Scalarm(p[2])));
    }
    out[e.key] = v;
  }
  return out;
}

pectus::Results fromVariantMap(const std::map<std::string, QVariant>& values) {
  pectus::Results r;
  for (const auto& [key, v] : values) {
    const int t = v.userType();
    if (t == qMetaTypeId<Point3m>()) {
      const Point3m p = v.value<Point3m>();
      r.set(key, pectus::Results::Vec3{double(p[0]), double(p[1]), double(p[2])});
    } else if (t == QMetaType::Double || t == QMetaType::Float) {
      r.set(key, v.toDouble());
    } else if (t == QMetaType::Int || t == QMetaType::LongLong || t == QMetaType::UInt || t == QMetaType::ULongLong) {
      r.set(key, v.toLongLong());
    } else if (t == QMetaType::Bool) {
      r.set(key, v.toBool() ? 1 : 0);
    } else if (t == QMetaType::QString) {
      r.set(key, v.toString().toStdString());
    }
  }
  return r;
}
#endif

std::string formatHistogram(const std::vector<std::size_t>& h) {
  std::ostringstream s;
  for (std::size_t i = 0; i < h.size(); ++i) s << (i ? " " : "") << h[i];
  return s.str();
}

std::string fmt(double v, int precision) { return pectus::fixedText(v, precision); }
QString num(double v) { return QString::fromStdString(pectus::significantText(v)); }

MeshModel* defaultLandmarkLayer(const MeshDocument& md) {
  for (MeshModel* m : meshes(md)) {
    QString l = m->label().toLower();
    const int dot = l.lastIndexOf('.');
    if (dot > 0) l = l.left(dot);
    if (l.endsWith("landmarks")) return m;
  }
  return currentMesh(md);
}

}  // namespace pectus::ml
