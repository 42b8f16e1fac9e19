// The adapter contract on a real MeshDocument (Debian's libmeshlab-common): a filter that modifies a
// layer, adds one, and then fails must leave the document exactly as it was, log why, and report the
// failure the host's way (2020.09: false + errorMessage; 2021.05+: MLException).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include <vcg/complex/algorithms/create/platonic.h>

#include "filter_plugin.h"
#include "pectus/errors.h"
#include "pectus/labels.h"

namespace {

class FakePlugin : public QObject, public pectus::ml::FilterPluginBase {
 public:
  enum { FP_BREAK, FP_OK, FP_CRASH, FP_PLAIN };  ///< FP_PLAIN: no numeric parameter
  std::function<void(pectus::ml::FilterContext&)> body;
  std::map<int, int> declarations;  ///< initParameters calls per filter
  FakePlugin() {
    pectus::ml::FilterSpec s;
    s.id = FP_BREAK; s.name = "Break"; s.info = "x"; addFilter(this, s);
    s.id = FP_OK; s.name = "Ok"; s.doc = "ok"; s.advanced = QStringList{"n"}; addFilter(this, s);
    s.doc.clear(); s.advanced.clear();
    s.id = FP_CRASH; s.name = "Crash"; addFilter(this, s);
    s.id = FP_PLAIN; s.name = "Plain"; addFilter(this, s);
  }
  QString pluginName() const override { return "Fake"; }
#if PECTUS_MESHLAB_API >= 2021
  // what MESHLAB_PLUGIN_IID_EXPORTER adds to a real plugin
  std::pair<std::string, bool> getMLVersion() const override {
    return {meshlab::meshlabVersion(), meshlab::builtWithDoublePrecision()};
  }
#endif
  void initParameters(int id, const MeshDocument&, RichParameterList& par) override {
    ++declarations[id];
    if (id == FP_PLAIN) {
      par.addParam(RichBool("flag", false, "flag", "A switch."));
      return;
    }
    pectus::ml::addFloat(par, "x", 1.0, "x", "A length (mm).", {0, 10, true, false});
    pectus::ml::addInt(par, "n", 3, "n", "", {1, 5});
  }
  void run(int id, pectus::ml::FilterContext& ctx) override {
    if (id == FP_CRASH) throw std::runtime_error("boom");
    body(ctx);
  }
};

QAction* action(FakePlugin& p, int i) { return *std::next(p.actions().begin(), i); }

RichParameterList params(FakePlugin& p, int i, MeshDocument& md) {
#if PECTUS_MESHLAB_API >= 2021
  return p.initParameterList(action(p, i), md);
#else
  RichParameterList par;
  p.initParameterSet(action(p, i), md, par);
  return par;
#endif
}

/// applies filter i as MeshLab does; the failure message, empty on success
QString apply(FakePlugin& p, int i, MeshDocument& md, const RichParameterList& par) {
#if PECTUS_MESHLAB_API >= 2021
  unsigned int mask = 0;
  try {
    p.applyFilter(action(p, i), par, md, mask, nullptr);
    return {};
  } catch (const MLException& e) {
    return QString(e.what()).isEmpty() ? QString("?") : QString(e.what());
  }
#else
  return p.applyFilter(action(p, i), md, par, nullptr) ? QString() : p.errorMsg();
#endif
}

std::size_t layers(const MeshDocument& md) { return pectus::ml::meshes(md).size(); }

std::vector<Scalarm> coords(const CMeshO& m) {
  std::vector<Scalarm> c;
  for (const auto& v : m.vert) for (int k = 0; k < 3; ++k) c.push_back(v.cP()[k]);
  return c;
}

}  // namespace

TEST(Adapter, FailedFilterRollsBackEveryLayer) {
  MeshDocument md;
  MeshModel* a = md.addNewMesh("", "a");
  vcg::tri::Icosahedron(a->cm);
  a->updateDataMask(MeshModel::MM_FACEQUALITY);
  for (auto& f : a->cm.face) f.Q() = 0.25f;
  pectus::writeFaceLabels(a->cm, std::vector<int>(a->cm.face.size(), 2), std::vector<int>(a->cm.face.size(), 107));
  const auto before = coords(a->cm);
  const int fn = a->cm.fn, mask = a->dataMask();

  FakePlugin p;
  p.body = [&](pectus::ml::FilterContext& ctx) {
    CMeshO& m = ctx.modify(ctx.current());
    for (auto& v : m.vert) v.P() *= 2.0f;
    vcg::tri::Allocator<CMeshO>::DeleteFace(m, m.face[0]);
    auto h = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(m, pectus::kTissueAttr);
    h[3] = 99;
    ctx.current().updateDataMask(MeshModel::MM_FACECOLOR | MeshModel::MM_VERTQUALITY);
    ctx.addLayer("new");
    throw pectus::InputError("parameter 'x' is wrong");
  };
  const RichParameterList par = params(p, 0, md);
  const QString err = apply(p, 0, md, par);
  EXPECT_EQ(layers(md), 1u);
  EXPECT_EQ(md.mm(), a);
  EXPECT_EQ(coords(a->cm), before);
  EXPECT_EQ(a->cm.fn, fn);
  EXPECT_FALSE(a->cm.face[0].IsD());
  EXPECT_EQ(a->dataMask(), mask);
  auto labels = pectus::readFaceLabels(a->cm);
  ASSERT_TRUE(labels.has_value());
  EXPECT_EQ(labels->tissue[3], 2);
  EXPECT_EQ(labels->part[3], 107);
  EXPECT_NE(err.indexOf("parameter 'x' is wrong"), -1);
  EXPECT_NE(err.indexOf("unchanged"), -1);
}

TEST(Adapter, ExceptionsNeverEscapeAndSuccessCommits) {
  MeshDocument md;
  MeshModel* a = md.addNewMesh("", "a");
  vcg::tri::Tetrahedron(a->cm);
  FakePlugin p;
  const RichParameterList par = params(p, 2, md);
  EXPECT_NE(apply(p, 2, md, par).indexOf("internal error: boom"), -1);

  p.body = [&](pectus::ml::FilterContext& ctx) {
    for (auto& v : ctx.modify(ctx.current()).vert) v.P() *= 3.0f;
    ctx.addLayer("kept");
  };
  EXPECT_TRUE(apply(p, 1, md, par).isEmpty());
  EXPECT_EQ(layers(md), 2u);
  EXPECT_FLOAT_EQ(std::abs(a->cm.vert[0].P()[0]), 3.0f);
}

TEST(Adapter, CheckedParametersNameTheParameter) {
  MeshDocument md;
  md.addNewMesh("", "a");
  RichParameterList par;
  par.addParam(RichFloat("accuracy", -1.0f, "Accuracy", ""));
  par.addParam(RichInt("count", 7, "Count", ""));
  const pectus::ml::DeclaredRanges ranges{{"accuracy", {{0, 1, true, false}, false}}, {"count", {{1, 5}, true}}};
  pectus::ml::FilterContext ctx(md, par, nullptr, nullptr, "t", &ranges);
  try {
    ctx.floatIn("accuracy");
    FAIL() << "no throw";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'accuracy' must be in (0, 1], got -1"), std::string::npos) << e.what();
  }
  try {
    ctx.intIn("count");
    FAIL() << "no throw";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'count' must be an integer in [1, 5], got 7"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ctx.intIn("accuracy"), std::logic_error);  // declared as a Float
  EXPECT_THROW(ctx.floatIn("undeclared"), std::logic_error);
  EXPECT_FLOAT_EQ(ctx.floatCheckedByCore("accuracy"), -1.0f);  // the core checks it
  EXPECT_EQ(ctx.intCheckedByCore("count"), 7);
  EXPECT_THROW(ctx.floatCheckedByCore("undeclared"), std::logic_error);
  ctx.commit();
}

// One declaration gives the tool-tip's range and the range run() checks, also when the host runs the
// filter without asking for its parameters first (a script).
TEST(Adapter, DeclaredRangeIsTheToolTipAndTheCheck) {
  MeshDocument md;
  md.addNewMesh("", "a");
  {
    FakePlugin p;
    RichParameterList par = params(p, 1, md);
    EXPECT_EQ(par.getParameterByName("x").toolTip(), QString("A length (mm). Range: (0, 10]."));
    EXPECT_EQ(par.getParameterByName("n").toolTip(), QString("Range: [1, 5]."));
    const QVariantList x = action(p, 1)->property(pectus::ml::FilterPluginBase::kRangesProperty).toMap()["x"].toList();
    ASSERT_EQ(x.size(), 5);
    EXPECT_EQ(x[0].toDouble(), 0.0);
    EXPECT_EQ(x[1].toDouble(), 10.0);
    EXPECT_TRUE(x[2].toBool());
    EXPECT_FALSE(x[3].toBool());
  }
  FakePlugin p;
  float seen = 0;
  p.body = [&](pectus::ml::FilterContext& ctx) { seen = ctx.floatIn("x") + float(ctx.intIn("n")); };
  RichParameterList ok;
  ok.addParam(RichFloat("x", 10.0f, "x", ""));
  ok.addParam(RichInt("n", 1, "n", ""));
  EXPECT_TRUE(apply(p, 1, md, ok).isEmpty());
  EXPECT_FLOAT_EQ(seen, 11.0f);
  RichParameterList bad;
  bad.addParam(RichFloat("x", 0.0f, "x", ""));
  bad.addParam(RichInt("n", 1, "n", ""));
  EXPECT_NE(apply(p, 1, md, bad).indexOf("parameter 'x' must be in (0, 10], got 0"), -1);
}

// MeshLab's float field shows 3 significant digits and applies what it shows: a default it would round
// (12.25 -> 12.3, 11500 -> 1.15e+04) is declared as a bounded float, shown as written, with the same value.
TEST(Adapter, FloatsAreShownAsWritten) {
  RichParameterList par;
  pectus::ml::addFloat(par, "cartilage", 12.25, "E", "", {0, 1e6, true, false});
  pectus::ml::addFloat(par, "bone", 11500, "E", "", {0, 1e6, true, false});
  pectus::ml::addFloat(par, "ratio", 0.4, "nu", "", {-1, 0.5, true, true});
  EXPECT_NE(dynamic_cast<const RichDynamicFloat*>(&par.getParameterByName("cartilage")), nullptr);
  EXPECT_NE(dynamic_cast<const RichDynamicFloat*>(&par.getParameterByName("bone")), nullptr);
  EXPECT_EQ(dynamic_cast<const RichDynamicFloat*>(&par.getParameterByName("ratio")), nullptr);
  EXPECT_FLOAT_EQ(par.getFloat("cartilage"), 12.25f);
  EXPECT_FLOAT_EQ(par.getFloat("bone"), 11500.0f);
  EXPECT_TRUE(pectus::ml::floatFieldRoundsShownValue(12.25));
  EXPECT_FALSE(pectus::ml::floatFieldRoundsShownValue(44.7));
}

// The dialog's description links the filter's docs page; a parameter listed as advanced is hidden until asked
// where MeshLab can (2021.05 and later).
TEST(Adapter, DialogLinksTheDocsAndMarksAdvancedParameters) {
  MeshDocument md;
  md.addNewMesh("", "a");
  FakePlugin p;
  EXPECT_NE(p.filterInfo(FakePlugin::FP_OK).indexOf("/filters/ok.md\">ok.md</a>"), -1);
  EXPECT_EQ(p.filterInfo(FakePlugin::FP_BREAK), QString("x"));
  const RichParameterList par = params(p, 1, md);
#if PECTUS_MESHLAB_API >= 2021
  EXPECT_TRUE(par.getParameterByName("n").isAdvanced());
  EXPECT_FALSE(par.getParameterByName("x").isAdvanced());
#else
  EXPECT_TRUE(par.hasParameter("n"));
#endif
}

// A script run declares a filter's parameters before its first run only, also when the filter has no numeric
// parameter (no range to record).
TEST(Adapter, ParametersAreDeclaredOnceWithoutNumericParameters) {
  MeshDocument md;
  md.addNewMesh("", "a");
  FakePlugin p;
  int runs = 0;
  p.body = [&](pectus::ml::FilterContext&) { ++runs; };
  RichParameterList plain;
  plain.addParam(RichBool("flag", true, "flag", ""));
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(apply(p, FakePlugin::FP_PLAIN, md, plain).isEmpty());
  EXPECT_EQ(runs, 3);
  EXPECT_EQ(p.declarations[FakePlugin::FP_PLAIN], 1);
  RichParameterList numeric;
  numeric.addParam(RichFloat("x", 1.0f, "x", ""));
  numeric.addParam(RichInt("n", 3, "n", ""));
  for (int i = 0; i < 2; ++i) EXPECT_TRUE(apply(p, FakePlugin::FP_OK, md, numeric).isEmpty());
  EXPECT_EQ(p.declarations[FakePlugin::FP_OK], 1);
  // declared when the host asks for the parameters: a run after that declares nothing more
  FakePlugin asked;
  asked.body = [](pectus::ml::FilterContext&) {};
  params(asked, FakePlugin::FP_PLAIN, md);
  EXPECT_TRUE(apply(asked, FakePlugin::FP_PLAIN, md, plain).isEmpty());
  EXPECT_EQ(asked.declarations[FakePlugin::FP_PLAIN], 1);
}

TEST(Adapter, NoCurrentLayerIsAMessage) {
  MeshDocument md;
  FakePlugin p;
  p.body = [](pectus::ml::FilterContext&) {};
  RichParameterList par;
  par.addParam(RichFloat("x", 1.0f, "x", "x"));
  par.addParam(RichInt("n", 3, "n", "n"));
  EXPECT_NE(apply(p, 1, md, par).indexOf("no current layer"), -1);
}

// The figures a filter puts into ctx.results() reach the host after a successful run: on 2021.05+ as
// applyFilter's return values; on 2020.09 as a JSON line in $PECTUS_RESULTS_FILE and a Log line; on every host
// as the JSON file the run names. A failed run returns, writes and logs none.
TEST(Adapter, ResultsReachTheHostAfterSuccessOnly) {
  const std::string dir = ::testing::TempDir();
  const std::string envFile = dir + "pectus_adapter_results.jsonl", beside = dir + "pectus_adapter_beside.json";
  std::remove(envFile.c_str());
  std::remove(beside.c_str());
  ASSERT_EQ(setenv("PECTUS_RESULTS_FILE", envFile.c_str(), 1), 0);
  auto read = [](const std::string& path) {
    std::ifstream f(path);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  };

  MeshDocument md;
  MeshModel* a = md.addNewMesh("", "a");
  vcg::tri::Tetrahedron(a->cm);
  FakePlugin p;
  p.setLog(&md.Log);
  const RichParameterList par = params(p, 1, md);
  p.body = [&](pectus::ml::FilterContext& ctx) {
    ctx.results().set("force_N", 14.5);
    ctx.results().set("solves", 7);
    ctx.results().set("max_stress_where", "sternum");
    ctx.results().set("max_stress_at_mm", pectus::Results::Vec3{1, 2, 3});
    ctx.writeResultsTo(beside);
  };
  const std::string line =
      R"({"filter": "Ok", "results": {"force_N": 14.5, "solves": 7, "max_stress_where": "sternum", "max_stress_at_mm": [1.0, 2.0, 3.0]}})";
#if PECTUS_MESHLAB_API >= 2021
  unsigned int mask = 0;
  const auto values = p.applyFilter(action(p, 1), par, md, mask, nullptr);
  ASSERT_EQ(values.size(), 4u);
  EXPECT_EQ(values.at("force_N").userType(), int(QMetaType::Double));
  EXPECT_DOUBLE_EQ(values.at("force_N").toDouble(), 14.5);
  EXPECT_EQ(values.at("solves").userType(), int(QMetaType::Int));
  EXPECT_EQ(values.at("solves").toInt(), 7);
  EXPECT_EQ(values.at("max_stress_where").toString(), QString("sternum"));
  ASSERT_EQ(values.at("max_stress_at_mm").userType(), qMetaTypeId<Point3m>());
  EXPECT_EQ(values.at("max_stress_at_mm").value<Point3m>(), Point3m(1, 2, 3));
  // the runner's converse gives the same JSON back (in the map's order of keys)
  EXPECT_EQ(pectus::ml::fromVariantMap(values).toJson(),
            R"({"force_N": 14.5, "max_stress_at_mm": [1.0, 2.0, 3.0], "max_stress_where": "sternum", "solves": 7})");
  EXPECT_EQ(read(envFile), "");  // pectus-mlrun writes the file from the return values
#else
  ASSERT_TRUE(apply(p, 1, md, par).isEmpty());
  EXPECT_EQ(read(envFile), line + "\n");
  QStringList log;
  md.Log.print(log);
  EXPECT_TRUE(log.join("\n").contains(R"(Results: force_N = 14.5, solves = 7, max_stress_where = "sternum", max_stress_at_mm = (1, 2, 3))"))
      << log.join("\n").toStdString();
#endif
  EXPECT_EQ(read(beside), line + "\n");

  // a failed run: nothing returned, nothing written
  std::remove(envFile.c_str());
  std::remove(beside.c_str());
  p.body = [&](pectus::ml::FilterContext& ctx) {
    ctx.results().set("force_N", 1.0);
    ctx.writeResultsTo(beside);
    throw pectus::SolverFailure("no convergence");
  };
  EXPECT_FALSE(apply(p, 1, md, par).isEmpty());
  EXPECT_FALSE(std::ifstream(envFile).good());
  EXPECT_FALSE(std::ifstream(beside).good());

  // a results file that cannot be written fails the run
  p.body = [&](pectus::ml::FilterContext& ctx) {
    ctx.results().set("force_N", 1.0);
    ctx.writeResultsTo(dir + "no/such/folder/results.json");
  };
  EXPECT_NE(apply(p, 1, md, par).indexOf("cannot write the results file"), -1);
  unsetenv("PECTUS_RESULTS_FILE");
}
