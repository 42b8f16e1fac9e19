// MeshLab adapter of the Nuss FE analysis (core/: pectus/nuss; the FE library pectus_fe): 'Nuss Procedure FE
// Analysis' and 'Pectus: Nuss Bar Planner'. Maps parameters, layers, progress, errors and results; no algorithm here.
#include "filter_nuss_fea.h"

#include <algorithm>
#include <chrono>

#include <QFileInfo>

#include "pectus/errors.h"
#include "pectus/fe/solver.h"
#include "pectus/labels.h"
#include "pectus/nuss/bar_planner.h"
#include "pectus/nuss/nuss_analysis.h"
#include "pectus/nuss/nuss_output.h"
#include "pectus/nuss/tissue_join.h"
#include "plot.h"

using pectus::ml::FilterContext;
using pectus::ml::fmt;
using pectus::ml::num;
using pectus::ml::addFloat;
using pectus::ml::addInt;

FilterNussFeaPlugin::FilterNussFeaPlugin() {
  pectus::fe::restBlasThreads();  // loaded with this plugin, OpenBLAS's idle threads would spin at start-up
  pectus::ml::FilterSpec n;
  n.id = FP_NUSS_FEA;
  n.name = "Pectus: Nuss Procedure FE Analysis";
  n.pythonName = "nuss_procedure_fe_analysis";
  n.info =
      "Finite element analysis of a Nuss repair on the labelled rib cage and its landmarks (thesis "
      "6.1-6.4): force, stress and strain.";
  n.doc = "nuss_fea";
  n.advanced = QStringList{"maxForce", "tolerance", "calibration", "newton", "tetQuality", "maxTetVolume",
                            "nuBone", "nuCartilage", "jointRadius", "sternumLoadRadius", "ribSupportRadius",
                            "pathSide", "pathRib"};
  n.cls = pectus::ml::HostFilter::Measure;
  n.arity = pectus::ml::HostFilter::VARIABLE;
  n.postCondition = MeshModel::MM_VERTQUALITY | MeshModel::MM_VERTCOLOR;
  addFilter(this, n);

  n.id = FP_BAR_PLANNER;  // same class, arity and post-conditions
  n.name = "Pectus: Nuss Bar Planner";
  n.pythonName = "nuss_bar_planner";
  n.info =
      "Compares bar levels, one bar against two: the calibrated FE analysis of each option, with force, "
      "stress, volume gain and index.";
  n.doc = "nuss_bar_planner";
  n.advanced = QStringList{"maxForce", "tolerance", "calibration", "newton", "tetQuality", "maxTetVolume",
                            "nuBone", "nuCartilage", "jointRadius", "sternumLoadRadius", "ribSupportRadius"};
  addFilter(this, n);

}

void FilterNussFeaPlugin::initParameters(int id, const MeshDocument& md, RichParameterList& par) {
  if (id == FP_NUSS_FEA) initNussFea(md, par);
  if (id == FP_BAR_PLANNER) initBarPlanner(md, par);
}

void FilterNussFeaPlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_NUSS_FEA: runNussFea(ctx); break;
    case FP_BAR_PLANNER: runBarPlanner(ctx); break;
    default: throw std::logic_error("unknown filter id");
  }
}


namespace {
QStringList orders() { return QStringList() << "Quadratic TET10 (no locking)" << "Linear TET4 (thesis, ANSYS SOLID185)"; }
QStringList analyses() { return QStringList() << "Large displacement (nonlinear)" << "Small strain (linear)"; }
QStringList materials() {
  return QStringList() << "St Venant-Kirchhoff" << "Neo-Hookean (FEBio)" << "Neo-Hookean (CalculiX hyperelastic)";
}
// the 'material' and 'calibration' entries, in the order of materials() and calibrations()
constexpr pectus::fe::MaterialModel kMaterials[] = {pectus::fe::MaterialModel::StVenantKirchhoff,
                                                    pectus::fe::MaterialModel::NeoHookean,
                                                    pectus::fe::MaterialModel::NeoHookeanDecoupled};
constexpr pectus::nuss::CalibrationMethod kCalibrations[] = {pectus::nuss::CalibrationMethod::ForceSearch,
                                                             pectus::nuss::CalibrationMethod::DisplacementControl};
template <class T, std::size_t N>
int entryOf(const T (&entries)[N], T value) {
  return int(std::find(entries, entries + N, value) - entries);
}
QStringList newtonSteps() { return QStringList() << "Line search and adaptive steps" << "Plain Newton, fixed steps"; }
QStringList calibrations() { return QStringList() << "Force search" << "Displacement control"; }
QStringList modes() { return QStringList() << "Calibrate Fe to the target elevation" << "Given elevating force"; }
QStringList fields() { return QStringList() << "von Mises stress (MPa)" << "Equivalent strain"; }
QStringList sides() { return QStringList() << "Right" << "Left"; }
}  // namespace

namespace {
// parameter groups shared by 'Pectus: Nuss Procedure FE Analysis' and 'Pectus: Nuss Bar Planner' (same names, defaults, help)
void addLandmarkParam(const MeshDocument& md, RichParameterList& par) {
  par.addParam(pectus::ml::richMesh("landmarkLayer", pectus::ml::defaultLandmarkLayer(md), md, "Landmark layer",
                        "Point layer of landmark codes (vertex quality), written with the cage."));
}
void addCalibrationParams(RichParameterList& par) {
  addFloat(par, "targetElevation", 0.0f, "Target elevation (mm)",
           "Rise of the lower sternum end; 0: up to the chest line.",
           pectus::nuss::kTargetElevationRange);
  addFloat(par, "maxForce", 1000.0f, "Maximum force (N)",
           "Calibration stops at this force.",
           pectus::nuss::kMaxForceRange);
  addFloat(par, "tolerance", 0.1f, "Calibration tolerance (mm)",
           "Allowed |simulated - target| elevation.", pectus::nuss::kToleranceRange);
  par.addParam(RichEnum("calibration", entryOf(kCalibrations, pectus::nuss::Options{}.calibration), calibrations(), "Calibration method",
                        "Force search: trial forces. Displacement control: one solve."));
}
void addModelParams(RichParameterList& par) {
  par.addParam(RichEnum("analysis", 0, analyses(), "Analysis",
                        "Large displacement: nonlinear (thesis: ANSYS). Small strain: linear."));
  const pectus::nuss::Options d;  // the analysis' defaults
  par.addParam(RichEnum("material", entryOf(kMaterials, d.material), materials(), "Material (large displacement)",
                        "Large displacement. Neo-Hookean resists tet inversion; SVK may invert."));
  par.addParam(RichEnum("newton", d.newton.lineSearch && d.newton.adaptiveSteps ? 0 : 1, newtonSteps(), "Newton steps",
                        "Line search with adaptive increments, or plain Newton, fixed steps."));
  par.addParam(RichEnum("order", 0, orders(), "Element",
                        "TET10: quadratic, accurate. TET4: the thesis' SOLID185, too stiff in bending."));
  addFloat(par, "tetQuality", 2.0f, "Tet quality (radius-edge ratio)",
           "TetGen -q: 0 none, else >= " + num(pectus::fe::kMinRadiusEdgeRatio) + "; smaller: finer.",
           {0, 100});
  addFloat(par, "maxTetVolume", 0.0f, "Max tet volume (mm^3)",
           "TetGen -a; 0: no limit.", {0, 1e9});
  addFloat(par, "boneModulus", d.eBone, "Young's modulus, bone (MPa)",
           "Ribs and sternum (thesis 11500).", pectus::nuss::kModulusRange);
  addFloat(par, "cartilageModulus", d.eCartilage, "Young's modulus, cartilage (MPa)",
           "Costal cartilage (thesis 12.25).", pectus::nuss::kModulusRange);
  addFloat(par, "nuBone", 0.3f, "Poisson ratio, bone",
           "Ribs and sternum (literature 0.3).", pectus::nuss::kPoissonRange);
  addFloat(par, "nuCartilage", 0.4f, "Poisson ratio, cartilage",
           "Costal cartilage (literature 0.4-0.45).",
           pectus::nuss::kPoissonRange);
}
void addPatchParams(RichParameterList& par) {
  addFloat(par, "jointRadius", 6.0f, "Joint radius (mm)",
           "Nodes this near a costovertebral joint are fixed.",
           pectus::nuss::kPatchRadiusRange);
  addFloat(par, "sternumLoadRadius", 8.0f, "Fe patch radius (mm)",
           "Fe acts on the sternum nodes this near its lower end.",
           pectus::nuss::kPatchRadiusRange);
  addFloat(par, "ribSupportRadius", 6.0f, "Fsr patch radius (mm)",
           "Each Fsr acts on the rib nodes this near the bar exit.", pectus::nuss::kPatchRadiusRange);
}

// the layers with faces the per-tissue input joins: every visible one
std::vector<const MeshModel*> tissueLayers(FilterContext& ctx) {
  std::vector<const MeshModel*> out;
  for (MeshModel* m : pectus::ml::meshes(ctx.doc()))
    if (m->isVisible() && m->cm.fn > 0) out.push_back(m);
  return out;
}
// the landmark layer of the cage (the current layer, or the tissue layers), found by role (FilterContext::landmarkLayer)
MeshModel& landmarkLayerOf(FilterContext& ctx, const std::vector<const MeshModel*>& cage) {
  return ctx.landmarkLayer("landmarkLayer", cage, std::vector<int>{pectus::kSternumLowerEnd},
                           "Pick the point layer of landmarks written with the cage (e.g. 'ribcage landmarks') and make the "
                           "labelled cage the current layer.",
                           {&ctx.current()});
}
void readCalibrationParams(FilterContext& ctx, pectus::nuss::Options& o, bool calibrate) {
  o.targetElevation = calibrate ? ctx.floatIn("targetElevation") : 0.0;
  o.targetFromChestLine = calibrate && o.targetElevation == 0;
  o.maxForce = ctx.floatIn("maxForce");
  o.tolerance = ctx.floatIn("tolerance");
  o.calibration = kCalibrations[ctx.enumIn("calibration", 2)];
}
void readModelParams(FilterContext& ctx, pectus::nuss::Options& o) {
  o.nonlinear = ctx.enumIn("analysis", 2) == 0;
  o.material = kMaterials[ctx.enumIn("material", 3)];
  o.newton.lineSearch = o.newton.adaptiveSteps = ctx.enumIn("newton", 2) == 0;
  o.mesh.order = ctx.enumIn("order", 2) == 0 ? 2 : 1;
  o.mesh.radiusEdgeRatio = ctx.floatIn("tetQuality");  // (0, 1.2) is refused by the core (fe::validate)
  o.mesh.maxVolume = ctx.floatIn("maxTetVolume");
  o.eBone = ctx.floatIn("boneModulus");
  o.eCartilage = ctx.floatIn("cartilageModulus");
  o.nuBone = ctx.floatIn("nuBone");
  o.nuCartilage = ctx.floatIn("nuCartilage");
}
void readPatchParams(FilterContext& ctx, pectus::nuss::Placement& pl) {
  pl.jointRadius = ctx.floatIn("jointRadius");
  pl.sternumLoadRadius = ctx.floatIn("sternumLoadRadius");
  pl.ribSupportRadius = ctx.floatIn("ribSupportRadius");
}

// the deformed surface of an analysis (nuss_output.h) as a new layer, coloured by the nodal field
// A result on a mesh coarser than the converged one says so, in the Log and in its values (reportable 0/1).
void reportMeshConvergence(FilterContext& ctx, const pectus::fe::TetgenOptions& mesh, const pectus::nuss::CageSurface& cage) {
  const std::string why = pectus::nuss::notReportableBecause(mesh, cage);
  ctx.results().set("reportable", why.empty() ? 1 : 0);
  if (why.empty()) return;
  ctx.results().set("not_reportable_because", why);
  ctx.log("Not a result to report: " + why + ". The defaults (TET10, tet quality 2) are within 2 % of the converged mesh.");
}

MeshModel& addDeformedLayer(FilterContext& ctx, CMeshO& surface, const pectus::nuss::CageSurface& cage,
                            const pectus::nuss::Analysis& a, const std::vector<double>& nodal, const QString& label) {
  MeshModel& res = ctx.addLayer(label);
  res.updateDataMask(MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY | MeshModel::MM_VERTQUALITY | MeshModel::MM_VERTCOLOR);
  pectus::nuss::deformedSurface(res.cm, surface, cage, a, nodal);
  return res;
}
}  // namespace

void FilterNussFeaPlugin::initNussFea(const MeshDocument& md, RichParameterList& par) {
  par.addParam(RichEnum("input", 0, QStringList() << "Current layer (one labelled surface)" << "One layer per tissue (visible layers)",
                        "Model input",
                        "One labelled surface, or every visible layer as one tissue, joined."));
  addLandmarkParam(md, par);
  addInt(par, "intercostalSpace", 4, "Bar intercostal space",
         "The bar exits between ribs s and s+1.", {1, 11});
  par.addParam(RichEnum("mode", 0, modes(), "Force",
                        "Calibrate: Fe for the target elevation. Given: the force below."));
  addFloat(par, "force", 140.0f, "Elevating force Fe (N)",
           "With 'Given elevating force'. Thesis: 70-190 N.", pectus::nuss::kForceRange);
  addCalibrationParams(par);
  addModelParams(par);
  addPatchParams(par);
  par.addParam(RichEnum("field", 0, fields(), "Colour by",
                        "Vertex quality and colour: von Mises stress (MPa) or equivalent strain."));
  par.addParam(RichEnum("pathSide", 0, sides(), "Strain path: side", "Side of the rib for the strain-path CSV (Fig. 6-18)."));
  addInt(par, "pathRib", 5, "Strain path: rib",
         "Rib (and its costal cartilage) for the strain-path CSV.", {1, 10});
  par.addParam(RichSaveFile("resultBase", "", ".vtu", "Result files (base name)",
                            "If set: BASE.vtu, .inp, _force_displacement.csv/.png, _rib_strain.csv."));
}

void FilterNussFeaPlugin::runNussFea(FilterContext& ctx) {
  namespace nuss = pectus::nuss;
  MeshModel& cur = ctx.current();

  nuss::Options o;
  const bool calibrate = ctx.enumIn("mode", 2) == 0;
  o.force = ctx.floatIn("force");
  readCalibrationParams(ctx, o, calibrate);
  readModelParams(ctx, o);
  o.place.intercostalSpace = ctx.intIn("intercostalSpace");
  readPatchParams(ctx, o.place);
  const bool stressField = ctx.enumIn("field", 2) == 0;
  const int pathSide = ctx.enumIn("pathSide", 2) + 1;
  const int pathRib = ctx.intIn("pathRib");
  const std::string base = nuss::resultBase(ctx.params().getSaveFileName("resultBase").trimmed().toStdString());
  o.progress = [&](int pc, const std::string& w) { ctx.progress(pc, w.c_str()); };

  // the model surface: the current labelled layer, or the visible tissue layers joined into `joined`
  const bool perTissue = ctx.enumIn("input", 2) == 1;
  std::vector<pectus::Landmark> lms;  // of the cage's landmark layer, found once the cage is known to be one
  pectus::OwnedMesh joined;
  std::string joinText;
  const auto cage = [&] {
    if (!perTissue) {
      auto c = nuss::cageFromMesh(cur.cm);
      lms = pectus::readLandmarks(landmarkLayerOf(ctx, {&cur}).cm);
      return c;
    }
    lms = pectus::readLandmarks(landmarkLayerOf(ctx, tissueLayers(ctx)).cm);
    std::vector<nuss::TissueLayer> layers;
    for (const MeshModel* m : tissueLayers(ctx)) layers.push_back({m->label().toStdString(), &m->cm});
    if (layers.empty())
      throw pectus::InputError("No visible layer with faces besides the landmark layer: load one closed surface per tissue.");
    nuss::JoinStats js;
    auto c = nuss::joinTissueLayers(layers, lms, joined, &js);
    joinText = "; joined " + std::to_string(js.layers) + " tissue layers: " + fmt(js.sumVolume / 1000, 2) + " cm^3 in the layers, " +
               fmt(js.unionVolume / 1000, 2) + " cm^3 in their union";
    return c;
  }();
  CMeshO& surfaceMesh = perTissue ? joined : cur.cm;
  const auto t0 = std::chrono::steady_clock::now();
  const nuss::Analysis a = nuss::analyze(cage, lms, o);

  // files first: a failure to write leaves the document unchanged
  std::string files;
  if (!base.empty()) {
    nuss::writeOutputs(nuss::filesAt(base, pathSide, pathRib), a, o);
    std::vector<std::pair<double, std::string>> hl;
    if (calibrate) hl.push_back({a.target.elevation, "target " + fmt(a.target.elevation, 1) + " mm"});
    pectus::ml::writeLinePlot(base + "_force_displacement.png", "Elevating force vs sternum end displacement (Fig. 6-14)",
                              "Elevating force Fe (N)", "Displacement of the end of the sternum (mm)",
                              {{o.nonlinear ? "large displacement" : "small strain", a.curve, 0x1f77b4, true}}, hl);
    files = "; files " + base + ".vtu/.inp/_force_displacement.csv/.png/_rib_strain.csv";
  }

  MeshModel& res = addDeformedLayer(ctx, surfaceMesh, cage, a, stressField ? a.nodalStress : a.nodalStrain, "nuss fe result");
  if (!perTissue) pectus::ml::recordSource(res, cur);  // the before layer of the volume filters

  std::vector<pectus::Landmark> moved = lms;
  for (auto& l : moved) l.p += a.displacementAt(l.p);
  MeshModel& lmAfter = ctx.addLayer("nuss landmarks after", false);
  lmAfter.updateDataMask(MeshModel::MM_VERTQUALITY);
  pectus::writeLandmarks(lmAfter.cm, moved);
  vcg::tri::UpdateBounding<CMeshO>::Box(lmAfter.cm);
  ctx.doc().setCurrentMesh(res.id());

  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ctx.log("Nuss FE model: " + std::to_string(a.mesh.numTets()) + (a.mesh.order == 2 ? " TET10" : " TET4") + " elements, " +
          std::to_string(a.mesh.numNodes()) + " nodes, " + std::to_string(a.fixedAtJoints) + " fixed nodes at the joints, Fe on " +
          std::to_string(a.sternumNodes.size()) + " sternum nodes, Fsr on " + a.supportNames[0] + "/" + a.supportNames[1] + "/" +
          a.supportNames[2] + "/" + a.supportNames[3] + (cage.weldedFaces ? "; welded " + std::to_string(cage.weldedFaces) + " sliver faces" : "") +
          (cage.unreferencedVertices ? "; dropped " + std::to_string(cage.unreferencedVertices) + " vertices of no face" : "") +
          joinText);
  ctx.log("Tissues (" + std::string(o.nonlinear ? pectus::fe::materialModelName(o.material) : "linear elastic") +
          "): bone E = " + fmt(o.eBone, 2) + " MPa, nu = " + fmt(o.nuBone, 2) + "; cartilage E = " + fmt(o.eCartilage, 2) +
          " MPa, nu = " + fmt(o.nuCartilage, 2));
  if (a.fixedOnColumn > 0)
    ctx.log("fixed: " + std::to_string(a.fixedAtJoints) + " nodes at the costovertebral joints, " + std::to_string(a.fixedOnColumn) +
            " on the vertebral column (part " + std::to_string(pectus::kVertebralColumn) + ", kept as the fixed support)");
  if (a.jointsWidened > 0)
    ctx.log(std::to_string(a.jointsWidened) + " costovertebral joints have fewer than 4 nodes of their rib within the joint radius (" +
            fmt(o.place.jointRadius, 1) + " mm): each is fixed at the 4 nodes of its rib nearest to it, more where those lie on one line (up to " + fmt(a.widestJointRadius, 1) + " mm away)");
  if (calibrate) ctx.log("Target elevation " + a.target.describe());
  ctx.log(std::string("Nuss FE result (") + (o.nonlinear ? "large displacement" : "small strain") + "): Fe = " + fmt(a.force, 2) +
          " N (Fs = " + fmt(a.force / 2, 2) + " N, Fsr = " + fmt(a.force / 4, 2) + " N)" +
          (calibrate ? ", calibrated to " + fmt(a.target.elevation, 2) + " mm in " + std::to_string(a.calibration->evaluations) + " solves" : "") +
          "; sternum end displacement " + fmt(a.elevation, 2) + " mm; linear compliance " + fmt(a.linearCompliance, 4) + " mm/N");
  ctx.log("Max von Mises stress " + fmt(a.maxStress, 2) + " MPa at the " + a.maxStressAt.describe() +
          " (away from the joints and load patches; " + fmt(a.maxStressAll, 2) + " MPa including them)");
  ctx.log("Max von Mises stress away from the tissue junctions " + fmt(a.maxStressBody, 2) + " MPa at the " +
          a.maxStressBodyAt.describe() + " (where a rib or the sternum meets its cartilage the stress is singular and grows as the mesh is refined)");
  ctx.log("Max equivalent strain " + fmt(a.maxStrain, 4) + " at the " + a.maxStrainAt.describe() + "; max in cartilage " +
          fmt(a.maxStrainCartilage, 4) + ", in bone " + fmt(a.maxStrainBone, 5));
  std::string curve;
  for (const auto& p : a.curve) curve += " " + fmt(p.first, 1) + ":" + fmt(p.second, 2);
  ctx.log("Force-displacement (N:mm)" + curve + "; " + std::to_string(a.nonlinearSolves) + " nonlinear solves, " +
          std::to_string(a.newtonIterations) + " Newton iterations; mesh " + fmt(a.secondsMesh, 1) + " s, solve " +
          fmt(a.secondsSolve, 1) + " s, total " + fmt(secs, 1) + " s" + files);
  for (const std::string& line : nuss::newtonHistoryLines(a)) ctx.debug("Newton " + line);

  auto& values = ctx.results();
  reportMeshConvergence(ctx, o.mesh, cage);
  values.set("tets", a.mesh.numTets());
  values.set("element", a.mesh.order == 2 ? "TET10" : "TET4");
  values.set("nodes", a.mesh.numNodes());
  values.set("analysis", o.nonlinear ? "large displacement" : "small strain");
  values.set("fixed_nodes_joints", a.fixedAtJoints);
  values.set("fixed_nodes_column", a.fixedOnColumn);
  values.set("sternum_nodes", a.sternumNodes.size());
  values.set("joints_widened", a.jointsWidened);
  if (calibrate) {
    values.set("target_elevation_mm", a.target.elevation);
    values.set("target_from", a.target.fromChestLine ? "from the model" : "as given");
    if (a.target.chest) values.set("chest_line_depth_mm", a.target.chest->depth);
    values.set("solves", a.calibration->evaluations);
  }
  values.set("force_N", a.force);
  values.set("elevation_mm", a.elevation);
  values.set("linear_compliance_mm_per_N", a.linearCompliance);
  auto place = [&](const std::string& key, double value, const nuss::Location& at) {
    values.set(key, value);
    values.set(key.substr(0, key.rfind('_')) + "_where", at.where());
    values.set(key.substr(0, key.rfind('_')) + "_at_mm", pectus::Results::Vec3{at.p.x(), at.p.y(), at.p.z()});
  };
  place("max_stress_MPa", a.maxStress, a.maxStressAt);
  values.set("max_stress_all_MPa", a.maxStressAll);
  place("max_stress_body_MPa", a.maxStressBody, a.maxStressBodyAt);
  values.set("max_strain", a.maxStrain);
  values.set("max_strain_where", a.maxStrainAt.where());
  values.set("max_strain_at_mm", pectus::Results::Vec3{a.maxStrainAt.p.x(), a.maxStrainAt.p.y(), a.maxStrainAt.p.z()});
  values.set("max_strain_cartilage", a.maxStrainCartilage);
  values.set("max_strain_bone", a.maxStrainBone);
  values.set("nonlinear_solves", a.nonlinearSolves);
  values.set("newton_iterations", a.newtonIterations);
  values.set("mesh_seconds", a.secondsMesh);
  values.set("solve_seconds", a.secondsSolve);
  values.set("seconds", secs);
  if (!base.empty()) ctx.writeResultsTo(base + "_results.json");  // beside the analysis' other files
}

namespace {
QStringList barSets() { return QStringList() << "One and two bars" << "One bar" << "Two bars"; }
QStringList bestBy() { return QStringList() << "Lowest force" << "Lowest max stress"; }
}  // namespace

void FilterNussFeaPlugin::initBarPlanner(const MeshDocument& md, RichParameterList& par) {
  addLandmarkParam(md, par);
  par.addParam(RichString("levels", "3,4,5", "Bar levels (intercostal spaces)",
                          "Spaces of the (first) bar, '3,4,5' or '3-5'; space s: ribs s and s+1."));
  par.addParam(RichEnum("bars", 0, barSets(), "Bars",
                        "One bar per level, two bars per level, or both (one row each)."));
  addInt(par, "secondOffset", -1, "Second bar: offset (spaces)",
         "Second bar's space: s + offset (-1: one above). Not 0.",
         pectus::nuss::kSecondOffsetRange);
  addFloat(par, "secondShare", 0.5f, "Second bar: share of the force",
           "Second bar's share of the total force.",
           pectus::nuss::kSecondShareRange);
  addCalibrationParams(par);
  addModelParams(par);
  addPatchParams(par);
  par.addParam(RichEnum("best", 0, bestBy(), "Best option",
                        "The option whose cage is added: lowest force or lowest max stress."));
  par.addParam(RichSaveFile("csvFile", "", ".csv", "Table (CSV file)",
                            "If set, the table is written there (one row per option). Empty: Log only."));
}

void FilterNussFeaPlugin::runBarPlanner(FilterContext& ctx) {
  namespace nuss = pectus::nuss;
  MeshModel& cur = ctx.current();
  const auto lms = pectus::readLandmarks(landmarkLayerOf(ctx, {&cur}).cm);
  nuss::PlanOptions o;
  o.levels = nuss::parseLevels(ctx.params().getString("levels").toStdString());
  const int bars = ctx.enumIn("bars", 3);
  o.oneBar = bars != 2;
  o.twoBars = bars != 1;
  o.secondOffset = ctx.intIn("secondOffset");
  o.secondShare = ctx.floatIn("secondShare");
  readCalibrationParams(ctx, o.analysis, true);
  readModelParams(ctx, o.analysis);
  readPatchParams(ctx, o.analysis.place);
  o.best = ctx.enumIn("best", 2) == 0 ? nuss::PlanOptions::Best::LowestForce : nuss::PlanOptions::Best::LowestStress;
  const std::string csv = ctx.params().getSaveFileName("csvFile").trimmed().toStdString();
  o.progress = [&](int pc, const std::string& w) { ctx.progress(pc, w.c_str()); };

  const auto cage = nuss::cageFromMesh(cur.cm);
  const nuss::Plan plan = nuss::planBars(cage, lms, o);
  if (!csv.empty()) nuss::writePlanCsv(csv, plan);  // before any layer: a failure leaves the document unchanged

  const nuss::PlanRow& best = plan.rows[plan.best];
  MeshModel& res = addDeformedLayer(ctx, cur.cm, cage, plan.bestAnalysis, plan.bestAnalysis.nodalStress,
                                    QString::fromStdString("nuss planner best: " + best.option));
  pectus::ml::recordSource(res, cur);
  ctx.doc().setCurrentMesh(res.id());

  const size_t n = plan.rows.size();
  ctx.log("Nuss bar planner: " + std::to_string(n) + " options, each calibrated to " + fmt(plan.target.elevation, 2) +
          " mm (" + (o.analysis.nonlinear ? "large displacement" : "small strain") + ", " + std::to_string(plan.tets) +
          (plan.order == 2 ? " TET10" : " TET4") + " elements meshed once in " + fmt(plan.secondsMesh, 1) + " s; reuse saved " +
          fmt(plan.secondsMesh * double(n - 1), 1) + " s of TetGen); before: slice " + fmt(plan.sliceBefore / 1000, 2) + " cm3, envelope " +
          fmt(plan.envelopeBefore / 1000, 2) + " cm3, Haller index " + fmt(plan.hallerBefore, 3));
  ctx.log("Target elevation " + plan.target.describe());
  for (const auto& line : nuss::planTable(plan)) ctx.log("Planner | " + line);
  for (const auto& r : plan.rows)
    ctx.log("Planner option '" + r.option + "': Fe = " + fmt(r.force, 2) + " N, elevation " + fmt(r.elevation, 2) +
            " mm; max von Mises stress " + fmt(r.maxStress, 2) + " MPa at the " + r.maxStressAt + "; max equivalent strain " +
            fmt(r.maxStrain, 4) + " at the " + r.maxStrainAt + "; volume gain slice " + fmt(r.sliceGain / 1000, 2) + " cm3 (" +
            fmt(r.slicePercent, 2) + " %), envelope " + fmt(r.envelopeGain / 1000, 2) + " cm3 (" + fmt(r.envelopePercent, 2) +
            " %); Haller index after " + fmt(r.hallerAfter, 3) + "; " + std::to_string(r.solves) + " solves, " + fmt(r.seconds, 1) + " s");
  ctx.log("Planner best (" + std::string(o.best == nuss::PlanOptions::Best::LowestForce ? "lowest force" : "lowest max stress") +
          "): '" + best.option + "', layer '" + res.label().toStdString() + "'; total " + fmt(plan.secondsTotal, 1) + " s" +
          (csv.empty() ? "" : "; table " + csv));

  auto& values = ctx.results();
  reportMeshConvergence(ctx, o.analysis.mesh, cage);
  values.set("options", n);
  values.set("target_elevation_mm", plan.target.elevation);
  values.set("tets", plan.tets);
  values.set("element", plan.order == 2 ? "TET10" : "TET4");
  values.set("mesh_seconds", plan.secondsMesh);
  values.set("before_slice_volume_cm3", plan.sliceBefore / 1000);
  values.set("before_envelope_volume_cm3", plan.envelopeBefore / 1000);
  values.set("before_haller_index", plan.hallerBefore);
  for (std::size_t i = 0; i < n; ++i) {  // option_1_... in the table's order
    const auto& r = plan.rows[i];
    const std::string k = "option_" + std::to_string(i + 1) + "_";
    values.set(k + "name", r.option);
    values.set(k + "bars", r.bars);
    values.set(k + "force_N", r.force);
    values.set(k + "elevation_mm", r.elevation);
    values.set(k + "max_stress_MPa", r.maxStress);
    values.set(k + "max_stress_where", r.maxStressWhere);
    values.set(k + "max_strain", r.maxStrain);
    values.set(k + "max_strain_where", r.maxStrainWhere);
    values.set(k + "slice_volume_change_cm3", r.sliceGain / 1000);
    values.set(k + "slice_volume_change_pct", r.slicePercent);
    values.set(k + "envelope_volume_change_cm3", r.envelopeGain / 1000);
    values.set(k + "envelope_volume_change_pct", r.envelopePercent);
    values.set(k + "haller_index_after", r.hallerAfter);
    values.set(k + "solves", r.solves);
    values.set(k + "seconds", r.seconds);
  }
  values.set("best_option", plan.best + 1);
  values.set("best_name", best.option);
  values.set("seconds", plan.secondsTotal);
}


MESHLAB_PLUGIN_NAME_EXPORTER(FilterNussFeaPlugin)
