#include "filter_mga_smooth.h"

#include <vcg/complex/algorithms/update/color.h>

#include "pectus/element_quality.h"
#include "pectus/errors.h"
#include "pectus/mesh_checks.h"

using pectus::ml::FilterContext;
using pectus::ml::fmt;

FilterMgaSmoothPlugin::FilterMgaSmoothPlugin() {
  pectus::ml::FilterSpec q;
  q.id = FP_ELEMENT_QUALITY;
  q.name = "Compute Element Quality (Triangle Alpha / Quad Beta)";
  q.info =
      "Shape quality of every element of the current layer, written to per-face quality and shown "
      "with MeshLab's quality colours (red = 0, poor; blue = 1, ideal).<br>"
      "<b>Triangles</b>: alpha = 2&radic;3 |AB&times;AC| / (|AB|&sup2;+|BC|&sup2;+|CA|&sup2;) (thesis eq. 3-20): "
      "1 for an equilateral triangle, 0 for a degenerate one.<br>"
      "<b>Quads</b> (MeshLab stores a quad as two triangles sharing a faux edge): Knupp's shape quality "
      "beta (eqs. 3-22/3-23), measured along the quad's own normal for surface quads: 1 for a square, "
      "towards 0 as an angle nears 180&deg;, 0 for a non-convex or inverted quad. Both triangles of a "
      "quad get its beta.<br>"
      "The Log gets min / mean / max and a 10-bin histogram. Empty layers, point clouds and NaN "
      "coordinates are refused with a message; asking for quads on a layer without faux edges is "
      "refused too (run a tri-to-quad conversion first).";
  q.cls = MeshFilterInterface::FilterClass(MeshFilterInterface::Quality | MeshFilterInterface::Measure);
  q.postCondition = MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
  addFilter(this, q);
}

void FilterMgaSmoothPlugin::initParameters(int id, MeshDocument&, RichParameterList& par) {
  if (id == FP_ELEMENT_QUALITY) {
    par.addParam(RichEnum("elementType", 0, QStringList() << "Auto" << "Triangles (alpha)" << "Quads (beta)",
                          "Element type",
                          "Auto: quads (beta) when the layer has faux edges (a quad or quad-dominant mesh), "
                          "else triangles (alpha). Triangles: every face is measured with alpha, faux edges "
                          "ignored. Quads: faux-edge pairs are measured with beta, lone triangles with alpha; "
                          "refused if the layer has no faux edge."));
    par.addParam(RichBool("colorize", true, "Colour by quality",
                          "Colour the faces with MeshLab's red-to-blue quality ramp on the fixed range [0, 1], "
                          "so colours compare across layers and before/after smoothing."));
  }
}

void FilterMgaSmoothPlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_ELEMENT_QUALITY: runElementQuality(ctx); break;
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
  CMeshO& m = ctx.modify(mm);
  mm.updateDataMask(MeshModel::MM_FACEQUALITY | (colorize ? MeshModel::MM_FACECOLOR : 0));
  for (std::size_t i = 0; i < m.face.size(); ++i)
    if (!m.face[i].IsD()) m.face[i].Q() = float(q.perFace[i]);
  if (colorize) vcg::tri::UpdateColor<CMeshO>::PerFaceQualityRamp(m, 0.0f, 1.0f);

  const bool quads = kind == pectus::ElementKind::Quads;
  std::string head = quads ? "Element quality (quad beta): " + std::to_string(q.mesh.quads()) + " quads" +
                                 (q.mesh.triangles() ? " + " + std::to_string(q.mesh.triangles()) + " triangles (alpha)" : "")
                           : "Element quality (triangle alpha): " + std::to_string(q.mesh.elements.size()) + " triangles";
  ctx.log(head + "; min " + fmt(q.stats.min) + " mean " + fmt(q.stats.mean) + " max " + fmt(q.stats.max) +
          "; invalid (not positive): " + std::to_string(q.stats.invalid));
  ctx.log("Element quality histogram, 10 bins on [0,1]: " + pectus::ml::formatHistogram(q.stats.histogram));
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterMgaSmoothPlugin)
