#include "filter_c1_surface.h"

#include <algorithm>
#include <cmath>

#include "pectus/c1/surface.h"
#include "pectus/surface_cmesh.h"
#include "pectus/c1/surface.h"
#include "pectus/errors.h"

using pectus::ml::FilterContext;
using pectus::ml::fmt;
using pectus::ml::addInt;
namespace c1 = pectus::c1;

namespace {

const QStringList kGradient = QStringList() << "Robust (minimum curvature / quadratic fit)" << "Thesis (inverse-area, eqs. 3-1/3-2)"
                                            << "Local quadratic fit (exact for quadratics)";
const QStringList kFrame = QStringList() << "3D surface (vertex normals)" << "Height field along Z";

const char* kGradientHelp =
    "Vertex normals: Robust (global or quadratic fit), Thesis (inverse-area mean), Local quadratic fit.";
const char* kFrameHelp = "3D surface: any oriented manifold mesh. Height field: the thesis' z = f(x, y), exactly C1.";

c1::Options options(FilterContext& ctx) {
  c1::Options o;
  const int g = ctx.enumIn("gradientMethod", 3);
  o.gradient = g == 1 ? c1::GradientMethod::InverseArea
                      : g == 2 ? c1::GradientMethod::QuadraticFit : c1::GradientMethod::MinimumCurvature;
  o.frame = ctx.enumIn("frame", 2) == 1 ? c1::Frame::HeightField : c1::Frame::VertexNormal;
  return o;
}

std::string describe(const c1::C1Surface& s) {
  const auto& st = s.stats();
  std::string r = std::to_string(st.faces) + " patches";
  if (st.degenerateFaces) r += ", " + std::to_string(st.degenerateFaces) + " zero-area faces (skipped in the gradients)";
  if (st.flatVertices) r += ", " + std::to_string(st.flatVertices) + " vertices without a frame (kept flat)";
  if (st.isolatedVertices) r += ", " + std::to_string(st.isolatedVertices) + " isolated vertices ignored";
  if (st.linearFitVertices) r += ", " + std::to_string(st.linearFitVertices) + " vertices with a plane fit (few neighbours)";
  return r;
}

void checkFaces(MeshModel& mm, const char* role) {
  if (mm.cm.fn == 0)
    throw pectus::InputError(std::string(role) + " layer '" + mm.label().toStdString() +
                             "' has no faces: the C1 surface is built on a triangle mesh");
}

}  // namespace

FilterC1SurfacePlugin::FilterC1SurfacePlugin() {
  pectus::ml::FilterSpec r;
  r.id = FP_C1_REFINE;
  r.name = "Pectus: C1 Refine onto Goodman-Said Surface";
  r.pythonName = "c1_surface_refine";
  r.info =
      "Splits every triangle of the current layer k&times;k, the new vertices on the layer's C1 "
      "Goodman-Said surface (thesis ch. 3).";
  r.doc = "c1_refine";
  r.advanced = QStringList{"gradientMethod", "frame"};
  r.cls = pectus::ml::HostFilter::Remeshing;
  r.postCondition = MeshModel::MM_VERTCOORD | MeshModel::MM_VERTNORMAL | MeshModel::MM_FACENUMBER |
                    MeshModel::MM_VERTNUMBER;
  addFilter(this, r);

  pectus::ml::FilterSpec p;
  p.id = FP_C1_PROJECT;
  p.name = "Pectus: C1 Project Layer onto Goodman-Said Surface";
  p.pythonName = "c1_surface_project_layer";
  p.info =
      "Moves every vertex of the current layer to the closest point of another layer's C1 Goodman-Said "
      "surface (thesis ch. 3).";
  p.doc = "c1_project";
  p.advanced = QStringList{"gradientMethod", "frame"};
  p.cls = pectus::ml::HostFilter::Smoothing;
  p.postCondition = MeshModel::MM_VERTCOORD | MeshModel::MM_VERTNORMAL;
  addFilter(this, p);
}

void FilterC1SurfacePlugin::initParameters(int id, const MeshDocument& md, RichParameterList& par) {
  if (id == FP_C1_REFINE) {
    addInt(par, "subdivisions", 3, "Subdivisions k",
           "Each triangle is split into k x k, new vertices on the C1 patches; 1 keeps the mesh.", c1::kSubdivisionsRange);
    par.addParam(RichEnum("gradientMethod", 0, kGradient, "Gradient estimation", kGradientHelp));
    par.addParam(RichEnum("frame", 0, kFrame, "Surface type", kFrameHelp));
    par.addParam(RichBool("newLayer", true, "Result in a new layer",
                          "Put the refined mesh into a new layer (the input stays); off: replace the current layer."));
  } else if (id == FP_C1_PROJECT) {
    MeshModel* def = pectus::ml::currentMesh(md);
    for (MeshModel* m : pectus::ml::meshes(md))
      if (m != pectus::ml::currentMesh(md) && m->cm.fn > 0) { def = m; break; }
    par.addParam(pectus::ml::richMesh("surfaceMesh", def, md, "Surface layer",
                          "Triangle mesh whose C1 surface the current layer's vertices are projected onto."));
    par.addParam(RichEnum("gradientMethod", 0, kGradient, "Gradient estimation", kGradientHelp));
    par.addParam(RichEnum("frame", 0, kFrame, "Surface type", kFrameHelp));
  }
}

void FilterC1SurfacePlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_C1_REFINE: runRefine(ctx); break;
    case FP_C1_PROJECT: runProject(ctx); break;
    default: throw std::logic_error("unknown filter id");
  }
}

void FilterC1SurfacePlugin::runRefine(FilterContext& ctx) {
  MeshModel& mm = ctx.current();
  const int k = ctx.intIn("subdivisions");
  const c1::Options opt = options(ctx);
  const bool newLayer = ctx.boolean("newLayer");
  checkFaces(mm, "the current");
  ctx.progress(5, "building the C1 surface");
  const c1::C1Surface surf(pectus::surfaceOf(mm.cm), opt);
  ctx.progress(40, "refining");
  std::vector<c1::Vec3> normals;
  const c1::TriMesh out = surf.refine(k, &normals);
  for (const auto& v : out.V)
    if (!v.allFinite()) throw std::runtime_error("C1 refinement produced a non-finite vertex (a bug: please report)");
  ctx.progress(85, "writing the mesh");
  const std::string label = mm.label().toStdString();
  MeshModel& dst = newLayer ? ctx.addLayer(mm.label() + QString(" C1 %1x%1").arg(k)) : mm;
  CMeshO& m = newLayer ? dst.cm : ctx.modify(dst);
  pectus::toMesh(out, m, &normals);
  if (!newLayer) dst.clearDataMask(MeshModel::MM_FACEFACETOPO | MeshModel::MM_VERTFACETOPO);
  vcg::tri::UpdateBounding<CMeshO>::Box(m);
  vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(m);
  ctx.log("C1 refine (Goodman-Said, " + std::string(opt.gradient == c1::GradientMethod::InverseArea ? "thesis" : "robust") +
          " gradients, " + (opt.frame == c1::Frame::HeightField ? "height field" : "3D") + "): layer '" + label + "' " +
          describe(surf) + "; split " + std::to_string(k) + "x" + std::to_string(k) + " -> " + std::to_string(out.V.size()) +
          " vertices, " + std::to_string(out.F.size()) + " faces" + (newLayer ? " in a new layer" : ""));
  ctx.results().set("vertices", out.V.size());
  ctx.results().set("faces", out.F.size());
}

void FilterC1SurfacePlugin::runProject(FilterContext& ctx) {
  MeshModel& target = ctx.current();
  MeshModel& src = ctx.mesh("surfaceMesh");
  const c1::Options opt = options(ctx);
  checkFaces(src, "the surface");
  if (target.cm.vn == 0) throw pectus::InputError("the current layer '" + target.label().toStdString() + "' has no vertices to project");
  ctx.progress(5, "building the C1 surface");
  const c1::C1Surface surf(pectus::surfaceOf(src.cm), opt);
  surf.buildIndex();
  ctx.progress(20, "projecting");
  std::vector<int> idx;
  std::vector<c1::Vec3> pts;
  for (std::size_t i = 0; i < target.cm.vert.size(); ++i) {
    const auto& v = target.cm.vert[i];
    if (v.IsD()) continue;
    const c1::Vec3 p = pectus::toEigen(v.cP());
    if (!p.allFinite())
      throw pectus::InputError("vertex " + std::to_string(i) + " of layer '" + target.label().toStdString() + "' has a NaN/Inf coordinate");
    idx.push_back(int(i));
    pts.push_back(p);
  }
  const int n = int(pts.size());
  std::vector<c1::SurfacePoint> res(n);
  const int chunk = std::max(1, n / 20);
  for (int c0 = 0; c0 < n; c0 += chunk) {
    const int c1e = std::min(n, c0 + chunk);
#pragma omp parallel for schedule(dynamic, 64)
    for (int i = c0; i < c1e; ++i) res[i] = surf.closestPoint(pts[i]);
    ctx.progress(20 + int(75.0 * c1e / n), "projecting");
  }
  double maxD = 0, sumD = 0;
  for (const auto& r : res) {
    if (!r.point.allFinite()) throw std::runtime_error("C1 projection produced a non-finite point (a bug: please report)");
    maxD = std::max(maxD, r.distance);
    sumD += r.distance;
  }
  CMeshO& m = ctx.modify(target);
  for (int i = 0; i < n; ++i) {
    m.vert[idx[i]].P() = pectus::toPoint(res[i].point);
    m.vert[idx[i]].N() = pectus::toPoint(res[i].normal);
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(m);
  if (m.fn) vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(m);
  ctx.log("C1 project: " + std::to_string(n) + " vertices of layer '" + target.label().toStdString() +
          "' moved onto the C1 surface of layer '" + src.label().toStdString() + "' (" + describe(surf) +
          "); displacement mean " + fmt(n ? sumD / n : 0.0, 6) + " max " + fmt(maxD, 6));
  ctx.results().set("vertices_moved", n);
  ctx.results().set("displacement_mean_mm", n ? sumD / n : 0.0);
  ctx.results().set("displacement_max_mm", maxD);
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterC1SurfacePlugin)
