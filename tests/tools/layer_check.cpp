// pectus_layer_check: runs one filter of this project's plugins on PLY layers in-process (as meshlabserver
// does) and saves every loaded layer before and after it, so that a test can compare them byte for byte.
// meshlabserver cannot show this: after a failed filter it exits without saving anything.
//
//   pectus_layer_check <plugin dir> <filter name> <params file> <out prefix> <in.ply>...
//   pectus_layer_check --params <plugin dir> [in.ply...]
//
// --params prints every filter of the plugins in <plugin dir> with its parameters as the plugin declares them
// (name, type, default, description, tool-tip; MeshLab's own .mlx form of each parameter) as one XML document,
// for the test that checks the docs' parameter tables. A numeric parameter declared with its range (addFloat,
// addInt in common/meshlab/filter_plugin.h) also has the attributes min, max, minOpen and maxOpen ("true" for
// an end that excludes its bound). The document holds the given layers, or one tetrahedron.
//
// params file: one parameter per line, "<type> <name> <value...>" with type Float, DynamicFloat, Int, Bool, Enum,
// Mesh (layer index), Point3 (x y z), String or SaveFile (the rest of the line). Parameters not listed
// keep the filter's defaults. Writes <out prefix>before_<i>.ply and <out prefix>after_<i>.ply (ascii,
// vertex/face quality and colour) and prints "applyFilter <0|1>". Exit code 0 unless the tool itself fails.
#include <QCoreApplication>
#include <QDir>
#include <QDomDocument>
#include <QPluginLoader>
#include <common/interfaces.h>
#include <wrap/io_trimesh/export_ply.h>
#include <wrap/io_trimesh/import_ply.h>
#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/algorithms/create/platonic.h>

#include <fstream>
#include <iostream>
#include <sstream>

namespace {

int fail(const std::string& msg) {
  std::cerr << "pectus_layer_check: " << msg << "\n";
  return 2;
}

void save(MeshModel& m, const std::string& path) {
  using namespace vcg::tri::io;
  int mask = Mask::IOM_VERTQUALITY | Mask::IOM_VERTCOLOR;
  if (m.cm.face.IsQualityEnabled()) mask |= Mask::IOM_FACEQUALITY;
  if (m.cm.face.IsColorEnabled()) mask |= Mask::IOM_FACECOLOR;
  ExporterPLY<CMeshO>::Save(m.cm, path.c_str(), mask, false);
}

struct LoadedFilter {
  MeshFilterInterface* plugin;
  QAction* action;
  QString library;
};

/// every filter of every MeshLab filter plugin (lib*.so) in `dir`
std::vector<LoadedFilter> loadFilters(const QString& dir) {
  std::vector<LoadedFilter> out;
  for (const QString& f : QDir(dir).entryList({"lib*.so"}, QDir::Files)) {
    auto* loader = new QPluginLoader(QDir(dir).absoluteFilePath(f));
    auto* p = qobject_cast<MeshFilterInterface*>(loader->instance());
    if (p == nullptr) continue;
    for (QAction* a : p->actions()) out.push_back({p, a, f});
  }
  return out;
}

/// the PLY files as layers of `md`; an error message, or empty
std::string loadLayers(MeshDocument& md, char** files, int count, std::vector<MeshModel*>& layers) {
  for (int i = 0; i < count; ++i) {
    MeshModel* m = md.addNewMesh(files[i], QFileInfo(files[i]).fileName(), true);
    int mask = 0;
    vcg::tri::io::ImporterPLY<CMeshO>::LoadMask(files[i], mask);
    m->Enable(mask);
    if (vcg::tri::io::ImporterPLY<CMeshO>::Open(m->cm, files[i], mask) != 0) return std::string("cannot read ") + files[i];
    vcg::tri::UpdateBounding<CMeshO>::Box(m->cm);
    if (!(mask & vcg::tri::io::Mask::IOM_VERTNORMAL)) vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFace(m->cm);
    layers.push_back(m);
  }
  return {};
}

int listParameters(int argc, char** argv) {
  MeshDocument md;
  std::vector<MeshModel*> layers;
  const std::string err = loadLayers(md, argv + 3, argc - 3, layers);
  if (!err.empty()) return fail(err);
  if (layers.empty()) {
    MeshModel* m = md.addNewMesh("", "tetrahedron", true);
    vcg::tri::Tetrahedron(m->cm);
    vcg::tri::UpdateBounding<CMeshO>::Box(m->cm);
    vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFace(m->cm);
  }
  QDomDocument doc;
  QDomElement root = doc.createElement("PectusFilters");
  doc.appendChild(root);
  for (const LoadedFilter& f : loadFilters(QString::fromUtf8(argv[2]))) {
    RichParameterList par;
    f.plugin->initParameterSet(f.action, md, par);
    QDomElement e = doc.createElement("filter");
    e.setAttribute("name", f.plugin->filterName(f.action));
    e.setAttribute("library", f.library);
    e.setAttribute("info", f.plugin->filterInfo(f.action));  // what the dialog shows above the parameters
    // the ranges the plugin base recorded during initParameterSet, on the filter's action
    // (FilterPluginBase::kRangesProperty: {lo, hi, loOpen, hiOpen, integer} by parameter name)
    const QVariantMap ranges = f.action->property("pectusParameterRanges").toMap();
    for (const RichParameter& p : par) {
      QDomElement pe = p.fillToXMLDocument(doc, true);
      const QVariantList r = ranges.value(p.name()).toList();
      if (r.size() == 5) {
        pe.setAttribute("min", QString::number(r[0].toDouble(), 'g', 17));
        pe.setAttribute("max", QString::number(r[1].toDouble(), 'g', 17));
        pe.setAttribute("minOpen", r[2].toBool() ? "true" : "false");
        pe.setAttribute("maxOpen", r[3].toBool() ? "true" : "false");
      }
      e.appendChild(pe);
    }
    root.appendChild(e);
  }
  std::cout << doc.toString(1).toStdString();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  QCoreApplication app(argc, argv);
  if (argc >= 3 && std::string(argv[1]) == "--params") return listParameters(argc, argv);
  if (argc < 6)
    return fail("usage: pectus_layer_check <plugin dir> <filter name> <params> <out prefix> <in.ply>...\n"
                "       pectus_layer_check --params <plugin dir> [in.ply...]");
  const QString filter = QString::fromUtf8(argv[2]);

  MeshFilterInterface* plugin = nullptr;
  QAction* action = nullptr;
  for (const LoadedFilter& f : loadFilters(QString::fromUtf8(argv[1])))
    if (f.plugin->filterName(f.action) == filter) plugin = f.plugin, action = f.action;
  if (action == nullptr) return fail("no plugin in " + std::string(argv[1]) + " has the filter " + argv[2]);

  MeshDocument md;
  std::vector<MeshModel*> layers;
  const std::string err = loadLayers(md, argv + 5, argc - 5, layers);
  if (!err.empty()) return fail(err);
  const std::string out = argv[4];
  for (std::size_t i = 0; i < layers.size(); ++i) save(*layers[i], out + "before_" + std::to_string(i) + ".ply");

  RichParameterList par;
  plugin->initParameterSet(action, md, par);
  std::ifstream in(argv[3]);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string type, name;
    if (!(s >> type >> name)) continue;
    const QString n = QString::fromStdString(name);
    if (!par.hasParameter(n)) return fail("the filter has no parameter " + name);
    if (type == "Float") { double v; s >> v; par.setValue(n, FloatValue(float(v))); }
    else if (type == "DynamicFloat") { double v; s >> v; par.setValue(n, DynamicFloatValue(float(v))); }
    else if (type == "Int") { long long v; s >> v; par.setValue(n, IntValue(int(v))); }
    else if (type == "Enum") { int v; s >> v; par.setValue(n, EnumValue(v)); }
    else if (type == "Bool") { int v; s >> v; par.setValue(n, BoolValue(v != 0)); }
    else if (type == "Mesh") {
      int v; s >> v;
      if (v < 0 || v >= int(layers.size())) return fail("layer index out of range for " + name);
      par.setValue(n, MeshValue(layers[v]));
    } else if (type == "Point3") { float x, y, z; s >> x >> y >> z; par.setValue(n, Point3fValue(vcg::Point3f(x, y, z))); }
    else {
      std::string rest;
      std::getline(s >> std::ws, rest);
      if (type == "SaveFile") par.setValue(n, FileValue(QString::fromStdString(rest)));
      else par.setValue(n, StringValue(QString::fromStdString(rest)));
    }
  }

  GLLogStream log;
  plugin->setLog(&log);
  const bool ok = plugin->applyFilter(action, md, par, nullptr);
  std::cout << "applyFilter " << (ok ? 1 : 0) << "\n";
  for (std::size_t i = 0; i < layers.size(); ++i) save(*layers[i], out + "after_" + std::to_string(i) + ".ply");
  return 0;
}
