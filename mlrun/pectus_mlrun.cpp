// pectus-mlrun: runs MeshLab filter scripts (.mlx) without a display, with the libmeshlab-common of
// MeshLab 2021.05 and later, which ship no meshlabserver. It takes meshlabserver's arguments, so the
// same scripts and tests run with either:
//
//   pectus-mlrun [-i in.ply]... [-s script.mlx] [-o out.ply [-l N] [-m vc fq ...]]... [-p plugin_dir]...
//
//   -i FILE       load a layer (any format MeshLab's I/O plugins read); repeatable
//   -s FILE       apply the filters of a MeshLab filter script, in order
//   -o FILE       save a layer after the script: -l N picks the layer (0 = first; default: the current
//                 one), -m the attributes to save (vc vf vq vn vt fc ff fq fn wc wn wt mp; sa: as text);
//                 a layer the document does not have is said and not saved, as meshlabserver does
//   -p DIR        load the filter plugins in DIR too (default: MeshLab's system plugin folder and the
//                 plugins folder beside this program's bin/; $PECTUS_MLRUN_PLUGINS adds folders, ':'-separated)
//   --list        print every filter loaded, with its pymeshlab name, and exit
//
// "Change the current layer" (MeshLab 2020.09's filter, gone from 2021.05 on, where the GUI picks the
// current layer by a click and pymeshlab by MeshSet.set_current_mesh) is carried out by the runner: a
// script that switches layers runs on every host.
//
// The filters' return values (pymeshlab's dict: a pectus filter's figures, pectus/results.h) are appended, when
// $PECTUS_RESULTS_FILE names a file, as one JSON line per filter applied: {"filter": "<name>", "results": {...}},
// as the plugins themselves write on 2020.09, so that scripts read the same file on every host.
//
// The filters' log lines reach standard error as "LOG: <level> <text>" (MeshLab's log prints them, as it
// did in meshlabserver). Exit status: 0 on
// success, 255 when a filter fails (its reason is in the log; every layer is left as it was), 2 for a bad
// argument, script or file. Unlike meshlabserver, a parameter of the wrong type in the script is a message,
// not an abort, and a missing one takes the filter's default with a warning.
#include <QApplication>
#include <QDir>
#include <QDomDocument>
#include <QFile>
#include <QFileInfo>
#include <QPluginLoader>

#include <common/filterscript.h>
#include <common/globals.h>
#include <common/mlexception.h>
#include <common/plugins/plugin_manager.h>
#include <common/utilities/load_save.h>

#include "filter_plugin.h"  // the results' JSON line and the return values' conversion
#include "pectus/errors.h"

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace {

struct Output {
  QString path;
  int layer = -1;  // -1: the current layer
  int mask = 0;
  bool ascii = false;  // "-m sa": a text file where the format has both (PLY)
};

struct Args {
  std::vector<QString> inputs;
  QString script;
  std::vector<Output> outputs;
  std::vector<QString> pluginDirs;
  bool list = false;
};

[[noreturn]] void usageError(const std::string& msg) {
  std::cerr << "pectus-mlrun: " << msg << "\n"
            << "usage: pectus-mlrun [-i in]... [-s script.mlx] [-o out [-l N] [-m vc fq ...]]... [-p plugin_dir]... [--list]\n";
  std::exit(2);
}

int maskBit(const std::string& t) {
  using M = vcg::tri::io::Mask;
  if (t == "vc") return M::IOM_VERTCOLOR;
  if (t == "vf") return M::IOM_VERTFLAGS;
  if (t == "vq") return M::IOM_VERTQUALITY;
  if (t == "vn") return M::IOM_VERTNORMAL;
  if (t == "vt") return M::IOM_VERTTEXCOORD;
  if (t == "vr") return M::IOM_VERTRADIUS;
  if (t == "fc") return M::IOM_FACECOLOR;
  if (t == "ff") return M::IOM_FACEFLAGS;
  if (t == "fq") return M::IOM_FACEQUALITY;
  if (t == "fn") return M::IOM_FACENORMAL;
  if (t == "wc") return M::IOM_WEDGCOLOR;
  if (t == "wn") return M::IOM_WEDGNORMAL;
  if (t == "wt") return M::IOM_WEDGTEXCOORD;
  if (t == "mp") return M::IOM_BITPOLYGONAL;
  usageError("unknown attribute '" + t + "' after -m (one of vc vf vq vn vt vr fc ff fq fn wc wn wt mp sa)");
}

Args parse(int argc, char** argv) {
  Args a;
  auto value = [&](int& i) -> QString {
    if (i + 1 >= argc) usageError(std::string(argv[i]) + " needs a value");
    return QString::fromLocal8Bit(argv[++i]);
  };
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "-i") {
      a.inputs.push_back(value(i));
      while (i + 1 < argc && argv[i + 1][0] != '-') a.inputs.push_back(QString::fromLocal8Bit(argv[++i]));
    } else if (s == "-s") {
      a.script = value(i);
    } else if (s == "-o") {
      a.outputs.push_back({value(i), -1, 0});
    } else if (s == "-l") {
      if (a.outputs.empty()) usageError("-l belongs after -o FILE");
      bool ok = false;
      a.outputs.back().layer = value(i).toInt(&ok);
      if (!ok || a.outputs.back().layer < 0) usageError("-l needs a layer number (0 = the first layer)");
    } else if (s == "-m") {
      if (a.outputs.empty()) usageError("-m belongs after -o FILE");
      while (i + 1 < argc && argv[i + 1][0] != '-') {
        const std::string t = argv[++i];
        if (t == "sa") a.outputs.back().ascii = true;
        else a.outputs.back().mask |= maskBit(t);
      }
    } else if (s == "-p") {
      a.pluginDirs.push_back(value(i));
    } else if (s == "--list") {
      a.list = true;
    } else if (s == "-h" || s == "--help") {
      usageError("runs MeshLab filter scripts without a display");
    } else {
      usageError("unknown argument '" + s + "'");
    }
  }
  return a;
}

bool quietProgress(const int, const char*) { return true; }

/// The release and scalar a plugin file was built for, from the plugin itself ("" if it is none).
std::string builtFor(const QString& file) {
  QPluginLoader loader(file);
  auto* p = dynamic_cast<MeshLabPlugin*>(loader.instance());
  if (p == nullptr) return loader.errorString().toStdString();
  const auto v = p->getMLVersion();
  return "built for MeshLab " + v.first + " with MESHLAB_SCALAR=" + (v.second ? "double" : "float");
}

std::string thisMeshLab() {
  return "MeshLab " + meshlab::meshlabVersion() + " with MESHLAB_SCALAR=" +
         (meshlab::builtWithDoublePrecision() ? "double" : "float");
}

/// Loads every plugin file of `dir`; one of ours that cannot load is named with the reason (a system
/// plugin that cannot load, e.g. for a library the meshlab package does not pull in, is only counted).
/// Returns false if one of ours failed.
bool loadDir(PluginManager& pm, const QString& dir, bool ours) {
  bool ok = true;
  QStringList skipped;
  QDir d(dir);
  // of MeshLab's own plugins only the filters and the file formats: the editing tools, decorators and
  // renderers belong to the GUI (and some need its library)
  const QStringList names = ours ? QStringList{"*.so"} : QStringList{"libfilter_*.so", "libio_*.so"};
  for (const QString& f : d.entryList(names, QDir::Files)) {
    const QString path = d.absoluteFilePath(f);
    try {
      pm.loadPlugin(path);
    } catch (const MLException& e) {
      std::string why = e.what();
      if (why.find("already loaded") != std::string::npos) continue;
      const QString iid = QPluginLoader(path).metaData().value("IID").toString();
      if (iid.contains("MeshFilterInterface"))
        why = path.toStdString() + " is a plugin for MeshLab 2020.09 or earlier (interface " + iid.toStdString() +
              "); this is " + thisMeshLab() + ": rebuild it against this MeshLab (scripts/host.sh)";
      else if (why.find("different version") != std::string::npos || why.find("precision") != std::string::npos ||
          why.find("scalar") != std::string::npos)
        why = path.toStdString() + " is " + builtFor(path) + "; this is " + thisMeshLab() +
              ": rebuild it against this MeshLab (scripts/host.sh)";
      if (ours) {
        std::cerr << "pectus-mlrun: plugin not loaded: " << why << "\n";
        ok = false;
      } else {
        skipped << f;
      }
    }
  }
  if (!skipped.isEmpty() && !qEnvironmentVariableIsEmpty("PECTUS_MLRUN_VERBOSE"))
    std::cerr << "pectus-mlrun: system plugins not loaded: " << skipped.join(" ").toStdString() << "\n";
  return ok;
}

/// The <Param> elements of each <filter> of a script, as written: name -> (type, value). MeshLab's
/// FilterScript drops a parameter whose value does not parse as its type; this names it.
using RawParams = std::vector<std::map<QString, std::pair<QString, QString>>>;
RawParams rawParameters(const QString& path) {
  RawParams out;
  QFile f(path);
  QDomDocument doc;
  if (!f.open(QIODevice::ReadOnly) || !doc.setContent(&f)) return out;
  for (QDomElement fe = doc.documentElement().firstChildElement("filter"); !fe.isNull();
       fe = fe.nextSiblingElement("filter")) {
    out.emplace_back();
    for (QDomElement pe = fe.firstChildElement("Param"); !pe.isNull(); pe = pe.nextSiblingElement("Param"))
      out.back()[pe.attribute("name")] = {pe.attribute("type"), pe.attribute("value")};
  }
  return out;
}

/// Every filter parameter of `defaults` takes the script's value of the same name and type. Returns the
/// problems (empty: all well); a missing parameter keeps its default (a warning in `notes`).
std::string mergeParameters(const QString& filter, RichParameterList& defaults, const RichParameterList& script,
                            const std::map<QString, std::pair<QString, QString>>& raw, std::vector<std::string>& notes) {
  std::string problems;
  for (RichParameter& p : defaults) {
    auto it = script.findParameter(p.name());
    auto r = raw.find(p.name());
    if (it == script.end() && r != raw.end()) {
      problems += "'" + filter.toStdString() + "': parameter '" + p.name().toStdString() + "' is written as " +
                  r->second.first.toStdString() + " with the value '" + r->second.second.toStdString() +
                  "', which does not read as one; the filter expects " + p.stringType().toStdString() + "\n";
      continue;
    }
    if (it == script.end()) {
      notes.push_back("'" + filter.toStdString() + "': parameter '" + p.name().toStdString() +
                      "' is not in the script; it keeps its default");
      continue;
    }
    if (it->stringType() != p.stringType()) {
      problems += "'" + filter.toStdString() + "': parameter '" + p.name().toStdString() + "' is " +
                  it->stringType().toStdString() + " in the script, the filter expects " +
                  p.stringType().toStdString() + "\n";
      continue;
    }
    p.setValue(it->value());
  }
  for (const RichParameter& s : script)
    if (defaults.findParameter(s.name()) == defaults.end())
      notes.push_back("'" + filter.toStdString() + "': the script's parameter '" + s.name().toStdString() +
                      "' is not one of the filter's; ignored");
  return problems;
}

MeshModel* layerAt(MeshDocument& md, int index) {
  int i = 0;
  for (MeshModel& m : md.meshIterator())
    if (i++ == index) return &m;
  return nullptr;
}

const QString kChangeLayer = "Change the current layer";

/// 2020.09's "Change the current layer": its parameter "layer" is the index of the layer to make current.
/// Returns "" or what is wrong.
std::string changeCurrentLayer(MeshDocument& md, const std::map<QString, std::pair<QString, QString>>& raw) {
  const auto it = raw.find("layer");
  bool ok = false;
  const int index = it == raw.end() ? -1 : it->second.second.toInt(&ok);
  if (!ok || index < 0)
    return "'" + kChangeLayer.toStdString() + "' needs a parameter 'layer' with a layer number (0 = the first layer)";
  MeshModel* m = layerAt(md, index);
  if (m == nullptr)
    return "'" + kChangeLayer.toStdString() + "': the document has no layer " + std::to_string(index) + " (" +
           std::to_string(md.meshNumber()) + " layers)";
  md.setCurrentMesh(m->id());
  md.Log.log(GLLogStream::FILTER, "Current layer: " + m->label().toStdString());
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  // Some plugins make icons and widgets when loaded: a GUI application on Qt's offscreen platform needs
  // no display
  if (qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM")) qputenv("QT_QPA_PLATFORM", "offscreen");
  QApplication app(argc, argv);
  const Args args = parse(argc, argv);

  PluginManager& pm = meshlab::pluginManagerInstance();
  // system plugins (I/O formats and MeshLab's own filters), then this project's
  const QString system = "/usr/lib/x86_64-linux-gnu/meshlab/plugins";
  loadDir(pm, QDir(system).exists() ? system : meshlab::defaultPluginPath(), false);
  std::vector<QString> dirs = args.pluginDirs;
  const QString beside = QDir(QCoreApplication::applicationDirPath()).absoluteFilePath("../plugins");
  if (dirs.empty() && QDir(beside).exists()) dirs.push_back(beside);
  for (const QString& d : QString::fromLocal8Bit(qgetenv("PECTUS_MLRUN_PLUGINS")).split(':', Qt::SkipEmptyParts))
    dirs.push_back(d);
  bool pluginsOk = true;
  for (const QString& d : dirs) {
    if (!QDir(d).exists()) usageError("plugin folder " + d.toStdString() + " does not exist");
    pluginsOk = loadDir(pm, d, true) && pluginsOk;
  }
  if (!pluginsOk) return 2;

  if (args.list) {
    for (FilterPlugin* fp : pm.filterPluginIterator())
      for (QAction* a : fp->actions())
        std::cout << fp->pythonFilterName(a).toStdString() << "\t" << fp->filterName(a).toStdString() << "\n";
    return 0;
  }

  MeshDocument md;
  for (const QString& in : args.inputs) {
    if (!QFileInfo(in).isFile()) {
      std::cerr << "pectus-mlrun: input " << in.toStdString() << " does not exist\n";
      return 2;
    }
    try {
      meshlab::loadMeshWithStandardParameters(in, md, quietProgress);
    } catch (const MLException& e) {
      std::cerr << "pectus-mlrun: cannot load " << in.toStdString() << ": " << e.what() << "\n";
      return 2;
    }
    std::cout << "Mesh " << in.toStdString() << " loaded has " << md.mm()->cm.vn << " vn " << md.mm()->cm.fn
              << " fn\n";
  }

  if (!args.script.isEmpty()) {
    FilterScript script;
    if (!QFileInfo(args.script).isFile() || !script.open(args.script)) {
      std::cerr << "pectus-mlrun: cannot read the filter script " << args.script.toStdString()
                << " (missing, not MeshLab's .mlx XML, or a parameter whose value does not parse)\n";
      return 2;
    }
    const RawParams raw = rawParameters(args.script);
    const std::string resultsFile = pectus::ml::resultsFileFromEnvironment();
    int stepIndex = 0;
    for (const auto& step : script) {
      static const std::map<QString, std::pair<QString, QString>> none;
      const auto& rawStep = stepIndex < int(raw.size()) ? raw[stepIndex] : none;
      ++stepIndex;
      const QString name = step.first;
      QAction* action = pm.filterAction(name);
      FilterPlugin* fp = action ? pm.getFilterPluginFromAction(action) : nullptr;
      if (fp == nullptr && name == kChangeLayer) {
        std::cout << "Applying filter " << name.toStdString() << "\n";
        const std::string problem = changeCurrentLayer(md, rawStep);
        if (!problem.empty()) {
          std::cout << "Problem with filter: " << problem << "\n";
          return 255;
        }
        continue;
      }
      if (fp == nullptr) {
        std::cerr << "pectus-mlrun: the script names a filter no loaded plugin has: '" << name.toStdString()
                  << "' (pectus-mlrun --list shows them)\n";
        return 2;
      }
      fp->setLog(&md.Log);
      RichParameterList par = fp->initParameterList(action, md);
      std::vector<std::string> notes;
      const std::string problems = mergeParameters(name, par, step.second, rawStep, notes);
      for (const auto& n : notes) md.Log.log(GLLogStream::WARNING, n);
      if (!problems.empty()) {
        std::cerr << "pectus-mlrun: the script's parameters do not fit the filter:\n" << problems;
        return 2;
      }
      std::cout << "Applying filter " << name.toStdString() << "\n";
      if (md.mm() != nullptr) md.mm()->updateDataMask(fp->getRequirements(action));
      unsigned int postCondition = fp->postCondition(action);
      try {
        const std::map<std::string, QVariant> values = fp->applyFilter(action, par, md, postCondition, quietProgress);
        if (!resultsFile.empty()) {
          const std::string line =
              pectus::ml::resultsJsonLine(name.toStdString(), pectus::ml::fromVariantMap(values));
          try {
            pectus::ml::appendLine(resultsFile, line);
          } catch (const pectus::IOError& e) {
            std::cerr << "pectus-mlrun: " << e.what() << "\n";
            return 2;
          }
        }
      } catch (const MLException& e) {
        std::cout << "Problem with filter: " << name.toStdString() << ": " << e.what() << "\n";
        return 255;
      } catch (const std::exception& e) {
        std::cout << "Problem with filter: " << name.toStdString() << ": " << e.what() << "\n";
        return 255;
      }
    }
  }

  for (const Output& o : args.outputs) {
    MeshModel* m = o.layer < 0 ? md.mm() : layerAt(md, o.layer);
    if (m == nullptr) {  // as meshlabserver: said, and the other outputs still saved
      std::cerr << "pectus-mlrun: no layer " << (o.layer < 0 ? std::string("is current") : std::to_string(o.layer))
                << " to save as " << o.path.toStdString() << " (" << md.meshNumber() << " layers): not saved\n";
      continue;
    }
    const QString ext = QFileInfo(o.path).suffix().toLower();
    IOPlugin* io = pm.outputMeshPlugin(ext);
    if (io == nullptr) {
      std::cerr << "pectus-mlrun: no plugin saves ." << ext.toStdString() << " files\n";
      return 2;
    }
    try {
      io->setLog(&md.Log);
      int capability = 0, defaultBits = 0;
      io->exportMaskCapability(ext, capability, defaultBits);
      const int mask = o.mask & capability;
      if (mask & vcg::tri::io::Mask::IOM_BITPOLYGONAL) m->updateDataMask(MeshModel::MM_FACEFACETOPO);
      RichParameterList savePar = io->initSaveParameter(ext, *m);
      if (savePar.hasParameter("Binary")) savePar.setValue("Binary", BoolValue(!o.ascii));
      io->save(ext, o.path, *m, mask, savePar, quietProgress);
    } catch (const MLException& e) {
      std::cerr << "pectus-mlrun: cannot save " << o.path.toStdString() << ": " << e.what() << "\n";
      return 2;
    }
    std::cout << "Mesh " << m->label().toStdString() << " saved as " << o.path.toStdString() << " ("
              << m->cm.vn << " vn " << m->cm.fn << " fn)\n";
  }
  return 0;
}
