#include "filter_mga_smooth.h"

#include <vcg/complex/algorithms/update/color.h>

#include "pectus/element_quality.h"
#include "pectus/errors.h"
#include "pectus/mesh_checks.h"
#include "pectus/smooth/mga_smooth.h"

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>

using pectus::ml::FilterContext;
using pectus::ml::fmt;
using pectus::ml::addFloat;
using pectus::ml::addInt;
namespace smooth = pectus::smooth;

namespace {
/// the micro-GA seed: any value of a non-negative Int
constexpr pectus::ParamRange kSeedRange{0, 2147483647};
/// Per-face quality (one value per face index) into `mm`, with MeshLab's red-to-blue ramp on [0, 1]
/// so that colours compare across layers and before/after smoothing. Call after ctx.modify(mm).
void writeFaceQuality(MeshModel& mm, const std::vector<double>& perFace, bool colorize) {
  mm.updateDataMask(MeshModel::MM_FACEQUALITY | (colorize ? MeshModel::MM_FACECOLOR : 0));
  CMeshO& m = mm.cm;
  for (std::size_t i = 0; i < m.face.size(); ++i)
    if (!m.face[i].IsD()) m.face[i].Q() = CMeshO::ScalarType(perFace[i]);
  if (colorize) vcg::tri::UpdateColor<CMeshO>::PerFaceQualityRamp(m, 0.0f, 1.0f);
}
}  // namespace

FilterMgaSmoothPlugin::FilterMgaSmoothPlugin() {
  pectus::ml::FilterSpec q;
  q.id = FP_ELEMENT_QUALITY;
  q.name = "Pectus: Element Quality (Triangle Alpha / Quad Beta)";
  q.pythonName = "compute_element_quality";
  q.info =
      "Shape quality of every element (triangle alpha, quad beta; thesis 3.4) as face quality and colours: "
      "red 0, poor; blue 1, ideal.";
  q.doc = "element_quality";
  q.cls = pectus::ml::HostFilter::Measure;
  q.postCondition = MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
  addFilter(this, q);

  pectus::ml::FilterSpec s;
  s.id = FP_MGA_SMOOTH;
  s.name = "Pectus: MGA Surface Mesh Smoothing";
  s.pythonName = "mga_surface_mesh_smoothing";
  s.info =
      "Better element shapes on a triangle or quad mesh: free nodes move on the mesh's own C1 surface by a "
      "micro-genetic search (thesis 4.2).";
  s.doc = "mga_smooth";
  s.advanced = QStringList{"tolerance", "accuracy", "generations", "restarts", "population", "selection",
                            "elementSearch", "minPassBelow", "featureAngle", "singularAngle", "seed"};
  s.cls = pectus::ml::HostFilter::Smoothing;
  s.postCondition = MeshModel::MM_VERTCOORD | MeshModel::MM_VERTNORMAL | MeshModel::MM_FACENORMAL |
                    MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
  addFilter(this, s);

  pectus::ml::FilterSpec g;
  g.id = FP_GRADIENT_SMOOTH;
  g.name = "Pectus: Gradient Surface Mesh Smoothing (Baseline)";
  g.pythonName = "gradient_surface_mesh_smoothing";
  g.info =
      "The conjugate gradient smoothing the thesis compares MGA with (Table 4-1): same fitness, surface, "
      "fixed nodes and guards.";
  g.doc = "gradient_smooth";
  g.advanced = QStringList{"tolerance", "cgIterations", "minPassBelow", "featureAngle", "singularAngle"};
  g.cls = s.cls;
  g.postCondition = s.postCondition;
  addFilter(this, g);
}

void FilterMgaSmoothPlugin::initParameters(int id, const MeshDocument&, RichParameterList& par) {
  if (id == FP_ELEMENT_QUALITY) {
    par.addParam(RichEnum("elementType", 0, QStringList() << "Auto" << "Triangles (alpha)" << "Quads (beta)",
                          "Element type",
                          "Auto: quads (beta) if the layer has faux edges, else triangles (alpha). "
                          "Quads needs faux edges."));
    par.addParam(RichBool("colorize", true, "Colour by quality",
                          "Colour faces by quality on a fixed red-to-blue ramp [0, 1], comparable across layers."));
  }
  if (id == FP_MGA_SMOOTH || id == FP_GRADIENT_SMOOTH) {
    const bool mga = id == FP_MGA_SMOOTH;
    par.addParam(RichEnum("elementType", 0, QStringList() << "Auto" << "Triangles (alpha)" << "Quads (beta)",
                          "Element type",
                          "Auto: quads (beta) if the layer has faux edges, else triangles (alpha). "
                          "Quads needs faux edges."));
    addInt(par, "maxSweeps", mga ? 10 : 15, "Maximum sweeps",
           "Upper bound on the number of passes over all free nodes (thesis step 9).", smooth::kMaxSweepsRange);
    addFloat(par, "tolerance", 1e-4f, "Convergence tolerance",
             "Stop when one sweep raises the mean element quality by less than this.", smooth::kToleranceRange);
    if (mga) {
      addFloat(par, "accuracy", 1e-3f, "Accuracy of r1, r2",
               "Wanted accuracy of r1, r2; sets the bits per parameter (eq. 1-1).", smooth::kAccuracyRange);
      addInt(par, "generations", 20, "Generations per element",
             "Micro-GA generations per element, restarts included. More: slower, better.",
             smooth::kGenerationsRange);
      addInt(par, "restarts", 4, "Restarts per element",
             "Max micro-GA restarts per element (a new population around the best).", smooth::kRestartsRange);
      addInt(par, "population", 5, "Population size",
             "Micro-GA population (the thesis uses 5, after Krishnakumar).", smooth::kPopulationRange);
      par.addParam(RichEnum("selection", 0, QStringList() << "Roulette wheel" << "Tournament", "Selection",
                            "Parent selection: roulette wheel (as in the thesis) or binary tournament."));
      par.addParam(RichEnum("elementSearch", 0,
                            QStringList() << "Every adjacent element (thesis)" << "Guided (faster)"
                                          << "Guided, local (fastest)",
                            "Element search",
                            "Thesis: every element around the node. Guided: about 2x faster. "
                            "Guided, local: 5-8x faster again."));
    } else {
      addInt(par, "cgIterations", 10, "CG iterations per node",
             "CG iterations per node and sweep (each a numerical gradient and a line search).", smooth::kCgIterationsRange);
    }
    addFloat(par, "worstGuard", pectus::smooth::kMinQualityGuard, "Worst-element guard",
             "A move may not drop the node's worst element below min(now, this). 0 = thesis' sum.", smooth::kQualityRange);
    addFloat(par, "minPassBelow", 0.0f, "Final worst-element pass below",
             "Up to 3 more sweeps lift worst elements below this (then the sum). 0 = off (thesis).", smooth::kQualityRange);
    par.addParam(RichEnum("featureDetection", 0, QStringList() << "Crease chains" << "Feature and singular angles",
                          "Feature detection",
                          "Fixed feature nodes: Crease chains (sharp edge chains, not noise) or the two angles below."));
    addFloat(par, "featureAngle", 60.0f, "Feature angle (degrees)",
             "Angles mode: nodes on an edge bent more than this (dihedral) are fixed; 180 = off.", smooth::kAngleRange);
    addFloat(par, "singularAngle", 90.0f, "Singular angle (degrees)",
             "Angles mode: nodes whose face normals spread more than this are fixed; 180 = off.", smooth::kAngleRange);
    par.addParam(RichEnum("selectionMode", 0,
                          QStringList() << "None" << "Smooth only selected vertices" << "Keep selected vertices fixed",
                          "Vertex selection",
                          "None: ignored. Smooth only selected, or keep selected fixed. "
                          "Boundary, feature nodes always fixed."));
    if (mga)
      addInt(par, "seed", 1, "Random seed",
             "Micro-GA seed; the same seed gives the same result on any thread count.", kSeedRange);
  }
}

void FilterMgaSmoothPlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_ELEMENT_QUALITY: runElementQuality(ctx); break;
    case FP_MGA_SMOOTH: runSmooth(ctx, true); break;
    case FP_GRADIENT_SMOOTH: runSmooth(ctx, false); break;
    default: throw std::logic_error("unknown filter id");
  }
}

void FilterMgaSmoothPlugin::runElementQuality(FilterContext& ctx) {
  MeshModel& mm = ctx.current();
  const int type = ctx.enumIn("elementType", 3);
  const bool colorize = ctx.boolean("colorize");
  pectus::requireMesh(mm.cm, {}, mm.label().toStdString());
  ctx.progress(10, "measuring elements");

  const bool faux = pectus::hasFauxEdges(mm.cm);
  if (type == 2 && !faux)
    throw pectus::InputError("quad quality was asked for, but layer '" + mm.label().toStdString() +
                             "' holds only triangles (no faux edges); convert it to quads first or choose "
                             "'Triangles (alpha)'");
  const auto kind = (type == 2 || (type == 0 && faux)) ? pectus::ElementKind::Quads : pectus::ElementKind::Triangles;
  const auto q = pectus::computeElementQuality(mm.cm, kind, 10);

  ctx.progress(80, "writing quality");
  ctx.modify(mm);
  writeFaceQuality(mm, q.perFace, colorize);

  const bool quads = kind == pectus::ElementKind::Quads;
  std::string head = quads ? "Element quality (quad beta): " + std::to_string(q.mesh.quads()) + " quads" +
                                 (q.mesh.triangles() ? " + " + std::to_string(q.mesh.triangles()) + " triangles (alpha)" : "")
                           : "Element quality (triangle alpha): " + std::to_string(q.mesh.elements.size()) + " triangles";
  ctx.log(head + "; min " + fmt(q.stats.min) + " mean " + fmt(q.stats.mean) + " max " + fmt(q.stats.max) +
          "; invalid (not positive): " + std::to_string(q.stats.invalid));
  ctx.log("Element quality histogram, 10 bins on [0,1]: " + pectus::ml::formatHistogram(q.stats.histogram));
  auto& res = ctx.results();
  res.set("element_kind", quads ? "quads" : "triangles");
  res.set("elements", q.mesh.elements.size());
  res.set("quads", quads ? q.mesh.quads() : 0);
  res.set("triangles", quads ? q.mesh.triangles() : q.mesh.elements.size());
  res.set("quality_min", q.stats.min);
  res.set("quality_mean", q.stats.mean);
  res.set("quality_max", q.stats.max);
  res.set("invalid_elements", q.stats.invalid);
  for (std::size_t i = 0; i < q.stats.histogram.size(); ++i)  // elements with quality in [i/10, (i+1)/10)
    res.set("histogram_" + std::to_string(i), q.stats.histogram[i]);
}

void FilterMgaSmoothPlugin::runSmooth(FilterContext& ctx, bool mga) {
  MeshModel& mm = ctx.current();
  const std::string layer = mm.label().toStdString();
  std::string what = mga ? "MGA smoothing" : "Gradient smoothing";
  pectus::smooth::Options o;
  o.method = mga ? pectus::smooth::Method::MicroGA : pectus::smooth::Method::ConjugateGradient;
  const int type = ctx.enumIn("elementType", 3);
  o.maxSweeps = ctx.intIn("maxSweeps");
  o.tolerance = ctx.floatIn("tolerance");
  if (mga) {
    o.accuracy = ctx.floatIn("accuracy");
    o.generations = ctx.intIn("generations");
    o.restarts = ctx.intIn("restarts");
    o.population = ctx.intIn("population");
    o.selection = ctx.enumIn("selection", 2) == 1 ? pectus::mga::Selection::Tournament : pectus::mga::Selection::Roulette;
    const int search = ctx.enumIn("elementSearch", 3);
    o.elementSearch = search == 2 ? pectus::smooth::ElementSearch::GuidedLocal
                    : search == 1 ? pectus::smooth::ElementSearch::Guided : pectus::smooth::ElementSearch::Every;
    if (search == 1) what += ", guided element search";
    if (search == 2) what += ", guided local element search";
    o.seed = std::uint64_t(std::uint32_t(ctx.intIn("seed")));
  } else {
    o.cgIterations = ctx.intIn("cgIterations");
  }
  o.worstGuard = ctx.floatIn("worstGuard");
  o.minPassBelow = ctx.floatIn("minPassBelow");
  o.features = ctx.enumIn("featureDetection", 2) == 1 ? pectus::smooth::FeatureDetection::Angles
                                                      : pectus::smooth::FeatureDetection::Creases;
  o.featureAngleDeg = ctx.floatIn("featureAngle");
  o.singularAngleDeg = ctx.floatIn("singularAngle");
  const int selMode = ctx.enumIn("selectionMode", 3);

  pectus::MeshRequirements req;
  req.edgeManifold = true;
  req.vertexManifold = true;
  pectus::requireMesh(mm.cm, req, layer);
  const bool faux = pectus::hasFauxEdges(mm.cm);
  if (type == 2 && !faux)
    throw pectus::InputError("quad smoothing was asked for, but layer '" + layer +
                             "' holds only triangles (no faux edges); convert it to quads first or choose "
                             "'Triangles (alpha)' or 'Auto'");
  o.kind = (type == 2 || (type == 0 && faux)) ? pectus::ElementKind::Quads : pectus::ElementKind::Triangles;

  std::vector<char> userFixed;
  if (selMode != 0) {
    const CMeshO& cm = mm.cm;
    userFixed.assign(cm.vert.size(), 0);
    std::size_t selected = 0;
    for (std::size_t i = 0; i < cm.vert.size(); ++i) {
      const bool s = !cm.vert[i].IsD() && cm.vert[i].IsS();
      selected += s;
      userFixed[i] = selMode == 1 ? !s : s;
    }
    if (selMode == 1 && selected == 0)
      throw pectus::InputError("'Smooth only selected vertices' was chosen, but layer '" + layer +
                               "' has no selected vertex; select vertices or choose 'None'");
  }

  o.progress = [&ctx, &o](int sweep, double mean) {
    ctx.progress(5 + int(90.0 * sweep / o.maxSweeps), ("sweep " + std::to_string(sweep) + ", mean quality " +
                                                       pectus::ml::fmt(mean)).c_str());
    return true;
  };
  ctx.progress(2, "building the C1 surface");
  const auto r = pectus::smooth::smoothMesh(mm.cm, o, userFixed);

  CMeshO& m = ctx.modify(mm);
  for (std::size_t i = 0; i < m.vert.size(); ++i)
    if (!m.vert[i].IsD())
      m.vert[i].P() = CMeshO::CoordType(CMeshO::ScalarType(r.positions[i].x()), CMeshO::ScalarType(r.positions[i].y()),
                                        CMeshO::ScalarType(r.positions[i].z()));
  writeFaceQuality(mm, r.perFace, true);
  vcg::tri::UpdateBounding<CMeshO>::Box(m);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFace(m);

  const bool quads = o.kind == pectus::ElementKind::Quads;
  const std::string q = quads ? "beta" : "alpha";
  ctx.log(what + " (" + std::string(quads ? "quads, beta" : "triangles, alpha") + "): " +
          std::to_string(r.elements) + " elements; worst " + q + " " + fmt(r.before.min) + " -> " + fmt(r.after.min) +
          ", mean " + q + " " + fmt(r.before.mean) + " -> " + fmt(r.after.mean) + "; nodes moved " +
          std::to_string(r.nodesMoved) + " of " + std::to_string(r.freeNodes) + " free" +
          (r.nodesPutBack ? " (" + std::to_string(r.nodesPutBack) + " put back: the surface crossed itself there)" : std::string()) +
          (r.nodesPutBackGuard ? " (" + std::to_string(r.nodesPutBackGuard) +
                                     " put back to keep the worst-element guard)"
                               : std::string()) +
          "; folds (elements facing against their edge neighbours) " + std::to_string(r.foldsBefore) + " -> " +
          std::to_string(r.foldsAfter) + ", " + std::to_string(r.foldsNew) + " new" +
          (r.movesUndoneForFolds + r.nodesPutBackFolds
               ? " (" + std::to_string(r.movesUndoneForFolds + r.nodesPutBackFolds) + " moves undone: they folded an element)"
               : std::string()) +
          "; sweeps " +
          std::to_string(r.sweeps) +
          (r.minPassSweeps ? " + " + std::to_string(r.minPassSweeps) + " worst-element" : std::string()) + "; time " + fmt(r.seconds, 2) + " s");
  ctx.log(what + ": fixed nodes: " + std::to_string(r.boundaryNodes) + " boundary, " +
          std::to_string(r.featureNodes) + " feature, " + std::to_string(r.singularNodes) + " singular, " +
          std::to_string(r.userFixedNodes) + " by the selection; " + std::to_string(r.colours) + " colours; " +
          std::to_string(r.evaluations) + " fitness evaluations; elements folded against a node's surface normal " +
          std::to_string(r.foldedBefore) + " -> " + std::to_string(r.foldedAfter));
  if (o.features == pectus::smooth::FeatureDetection::Creases) ctx.log(what + ": features: " + r.featureSummary);
  auto& res = ctx.results();
  res.set("element_kind", quads ? "quads" : "triangles");
  res.set("elements", r.elements);
  res.set("quality_min_before", r.before.min);
  res.set("quality_min_after", r.after.min);
  res.set("quality_mean_before", r.before.mean);
  res.set("quality_mean_after", r.after.mean);
  res.set("nodes_moved", r.nodesMoved);
  res.set("free_nodes", r.freeNodes);
  res.set("nodes_put_back", r.nodesPutBack);
  res.set("sweeps", r.sweeps);
  res.set("worst_element_sweeps", r.minPassSweeps);
  res.set("boundary_nodes", r.boundaryNodes);
  res.set("feature_nodes", r.featureNodes);
  res.set("singular_nodes", r.singularNodes);
  res.set("selection_fixed_nodes", r.userFixedNodes);
  res.set("colours", r.colours);
  res.set("fitness_evaluations", r.evaluations);
  res.set("folded_before", r.foldedBefore);
  res.set("folded_after", r.foldedAfter);
  res.set("folds_before", r.foldsBefore);
  res.set("folds_after", r.foldsAfter);
  res.set("folds_new", r.foldsNew);
  res.set("moves_undone_for_folds", r.movesUndoneForFolds + r.nodesPutBackFolds);
  res.set("nodes_put_back_guard", r.nodesPutBackGuard);
  res.set("seconds", r.seconds);
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterMgaSmoothPlugin)
