#include "filter_quad_convert.h"

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/color.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/algorithms/update/topology.h>

#include "pectus/c1/surface.h"
#include "pectus/surface_cmesh.h"
#include "pectus/elements.h"
#include "pectus/errors.h"
#include "pectus/mesh_checks.h"
#include "pectus/quad/poly_io.h"
#include "pectus/quad/poly_mesh.h"
#include "pectus/quad/quad_convert.h"
#include "pectus/quad/structure.h"

using pectus::ml::FilterContext;
using pectus::ml::fmt;
using pectus::ml::addFloat;
using pectus::ml::addInt;

namespace {
/// the dihedral limit of pairing and of the structure operators (degrees)
constexpr pectus::ParamRange kDihedralRange{0, 180, true, false};
}  // namespace
namespace pq = pectus::quad;

namespace {
/// Writes `p` into the layer (quads as faux-edge triangle pairs), per-face quality = the element's beta or
/// alpha with MeshLab's red-to-blue ramp on [0, 1]. Call after ctx.modify(mm).
void writeLayer(MeshModel& mm, const pq::PolyMesh& p) {
  CMeshO& m = mm.cm;
  pq::toCMesh(p, m);
  mm.updateDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
  std::size_t k = 0;
  for (const auto& f : p.F) {
    const auto q = CMeshO::ScalarType(pq::polyQuality(p, f));
    for (int j = 0; j < (f.nv == 4 ? 2 : 1); ++j) m.face[k++].Q() = q;
  }
  vcg::tri::UpdateColor<CMeshO>::PerFaceQualityRamp(m, 0.0f, 1.0f);
  if (mm.hasDataMask(MeshModel::MM_FACEFACETOPO)) vcg::tri::UpdateTopology<CMeshO>::FaceFace(m);
  if (mm.hasDataMask(MeshModel::MM_VERTFACETOPO)) vcg::tri::UpdateTopology<CMeshO>::VertexFace(m);
  vcg::tri::UpdateBounding<CMeshO>::Box(m);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFace(m);
}

std::string valenceLine(const std::vector<std::size_t>& h) {
  std::string s;
  for (std::size_t v = 1; v < h.size(); ++v) {
    if (!h[v]) continue;
    if (!s.empty()) s += ", ";
    s += std::to_string(v) + (v + 1 == h.size() ? "+" : "") + ":" + std::to_string(h[v]);
  }
  return s.empty() ? "(no interior node)" : s;
}

void requireManifold(const MeshModel& mm) {
  pectus::MeshRequirements req;
  req.edgeManifold = true;
  req.vertexManifold = true;
  pectus::requireMesh(mm.cm, req, mm.label().toStdString());
}
}  // namespace

FilterQuadConvertPlugin::FilterQuadConvertPlugin() {
  const auto cls = pectus::ml::HostFilter::Polygonal;
  pectus::ml::FilterSpec c;
  c.id = FP_TRI_TO_QUAD;
  c.name = "Pectus: Convert Triangles to Quads";
  c.pythonName = "convert_triangles_to_quads";
  c.info =
      "Merges pairs of adjacent triangles into quads (thesis 4.1.2) by an optimal (blossom) or a greedy "
      "pairing.";
  c.doc = "tri_to_quad";
  c.advanced = QStringList{"maxDihedral"};
  c.cls = cls;
  c.postCondition = MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE | MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
  addFilter(this, c);

  pectus::ml::FilterSpec s;
  s.id = FP_STRUCTURE;
  s.name = "Pectus: Quad Mesh Structure Improvement";
  s.pythonName = "mesh_structure_improvement";
  s.info =
      "Edge swapping, node elimination and edge division on a triangle or quad mesh (thesis 4.1.3), until "
      "none improves it.";
  s.doc = "structure";
  s.advanced = QStringList{"longEdgeFactor", "maxDihedral", "maxPasses"};
  s.cls = cls;
  s.postCondition = MeshModel::MM_GEOMETRY_AND_TOPOLOGY_CHANGE | MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR;
  addFilter(this, s);

  pectus::ml::FilterSpec w;
  w.id = FP_SAVE_POLY;
  w.name = "Pectus: Save Polygonal Mesh";
  w.pythonName = "save_polygonal_mesh";
  w.info =
      "Writes the current layer with real quads as OBJ, OFF or legacy VTK (MeshLab's own exporters write "
      "quads as triangles).";
  w.doc = "save_polygonal";
  w.cls = pectus::ml::HostFilter::Polygonal;
  addFilter(this, w);
}

void FilterQuadConvertPlugin::initParameters(int id, const MeshDocument&, RichParameterList& par) {
  if (id == FP_TRI_TO_QUAD) {
    par.addParam(RichEnum("pairing", 0, QStringList() << "Optimal (maximum-weight matching)" << "Greedy (by quad quality)",
                          "Pairing",
                          "Optimal: maximum total beta matching of the dual graph (Blossom). "
                          "Greedy: thesis, best quads first."));
    par.addParam(RichEnum("leftovers", 0, QStringList() << "All quads" << "Quad-dominant", "Leftover triangles",
                          "All quads: split every element once if triangles remain (C1 surface). "
                          "Quad-dominant: keep them."));
    addFloat(par, "minQuality", 0.0f, "Minimum quad quality (beta)",
             "Pairs with quad beta <= this stay apart; 0 excludes only non-convex, inverted quads.", {0, 1, false, true});
    addFloat(par, "maxDihedral", 60.0f, "Dihedral limit (degrees)",
             "Pairs whose normals differ by more than this are not merged (keeps creases).", kDihedralRange);
  }
  if (id == FP_STRUCTURE) {
    par.addParam(RichBool("edgeSwap", true, "Edge swapping", "Swap edges toward the ideal valence (6 / 4)."));
    par.addParam(RichBool("nodeElimination", true, "Node elimination",
                          "Remove interior nodes with too few elements (triangles: 3; quads: 2, 3)."));
    par.addParam(RichBool("edgeDividing", true, "Edge dividing", "Divide long interior edges at their middle."));
    addFloat(par, "longEdgeFactor", 1.6f, "Long edge factor",
             "An interior edge longer than this times the mean edge length is divided.", {1, 100, true, false});
    addFloat(par, "maxDihedral", 30.0f, "Dihedral limit (degrees)",
             "Operators act only where element normals differ by at most this (keeps the shape).", kDihedralRange);
    addInt(par, "maxPasses", 10, "Maximum passes",
           "Upper bound on the passes over the mesh.", {1, 1000});
  }
  if (id == FP_SAVE_POLY) {
    par.addParam(RichSaveFile("fileName", "quads.obj", ".obj", "File", "The file to write (its folder must exist)."));
    par.addParam(RichEnum("format", 0, QStringList() << "OBJ" << "OFF" << "VTK (legacy polydata)", "Format",
                          "OBJ: v / f records. OFF: polygon lists. VTK: legacy ASCII POLYDATA with POLYGONS."));
  }
}

void FilterQuadConvertPlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_TRI_TO_QUAD: runConvert(ctx); break;
    case FP_STRUCTURE: runStructure(ctx); break;
    case FP_SAVE_POLY: runSave(ctx); break;
    default: throw std::logic_error("unknown filter id");
  }
}

void FilterQuadConvertPlugin::runConvert(FilterContext& ctx) {
  MeshModel& mm = ctx.current();
  const std::string layer = mm.label().toStdString();
  pq::ConvertOptions o;
  o.pairing = ctx.enumIn("pairing", 2) == 1 ? pq::Pairing::Greedy : pq::Pairing::Optimal;
  o.leftovers = ctx.enumIn("leftovers", 2) == 1 ? pq::Leftovers::QuadDominant : pq::Leftovers::AllQuads;
  o.minQuality = ctx.floatIn("minQuality");
  o.maxDihedralDeg = ctx.floatIn("maxDihedral");
  requireManifold(mm);
  if (pectus::hasFauxEdges(mm.cm))
    throw pectus::InputError("layer '" + layer + "' already holds quads or polygons (faux edges); "
                             "convert a triangle mesh, or use 'Pectus: Quad Mesh Structure Improvement' on the quads");
  ctx.progress(5, "pairing triangles");
  const auto tri = pectus::surfaceOf(mm.cm);
  const auto r = pq::convertToQuads(tri, o);

  ctx.progress(90, "writing quads");
  ctx.modify(mm);
  writeLayer(mm, r.mesh);
  const auto& s = r.stats;
  ctx.log("Pectus: Convert Triangles to Quads (" + std::string(o.pairing == pq::Pairing::Greedy ? "greedy" : "optimal") + ", " +
          (o.leftovers == pq::Leftovers::AllQuads ? "all quads" : "quad-dominant") + "): " + std::to_string(tri.F.size()) +
          " triangles, " + std::to_string(r.candidates) + " candidate pairs, " + std::to_string(r.merged) +
          " merged, " + std::to_string(r.leftoverTriangles) + " left over" +
          (r.subdivided ? "; split into quads (" + std::to_string(r.newNodes) + " new nodes on the C1 surface)" : ""));
  ctx.log("Quads: " + fmt(s.quadPercent, 1) + "% quads (" + std::to_string(s.quads) + " quads, " +
          std::to_string(s.triangles) + " triangles); invalid quads (beta <= 0): " + std::to_string(s.invalidQuads) +
          "; beta min " + fmt(s.beta.min) + " mean " + fmt(s.beta.mean) + "; time " + fmt(r.seconds, 3) + " s");
  auto& res = ctx.results();
  res.set("input_triangles", tri.F.size());
  res.set("candidate_pairs", r.candidates);
  res.set("merged_pairs", r.merged);
  res.set("leftover_triangles", r.leftoverTriangles);
  res.set("new_nodes", r.newNodes);
  res.set("quads", s.quads);
  res.set("triangles", s.triangles);
  res.set("quad_pct", s.quadPercent);
  res.set("invalid_quads", s.invalidQuads);
  res.set("quality_min", s.beta.min);
  res.set("quality_mean", s.beta.mean);
  res.set("seconds", r.seconds);
}

void FilterQuadConvertPlugin::runStructure(FilterContext& ctx) {
  MeshModel& mm = ctx.current();
  pq::StructureOptions o;
  o.swap = ctx.boolean("edgeSwap");
  o.eliminate = ctx.boolean("nodeElimination");
  o.divide = ctx.boolean("edgeDividing");
  o.longEdgeFactor = ctx.floatIn("longEdgeFactor");
  o.maxDihedralDeg = ctx.floatIn("maxDihedral");
  o.maxPasses = ctx.intIn("maxPasses");
  requireManifold(mm);
  const bool quads = pectus::hasFauxEdges(mm.cm);
  const auto pm = pq::fromCMesh(mm.cm, quads);
  ctx.progress(5, "building the C1 surface");
  pectus::c1::C1Surface surface(pectus::surfaceOf(mm.cm));
  surface.buildIndex();
  ctx.progress(20, "structure operators");
  const auto r = pq::improveStructure(pm, &surface, o);

  ctx.modify(mm);
  writeLayer(mm, r.mesh);
  const auto& b = r.before;
  const auto& a = r.after;
  const std::string q = quads ? "beta" : "alpha";
  const auto& qb = quads ? b.beta : b.alpha;
  const auto& qa = quads ? a.beta : a.alpha;
  ctx.log("Pectus: Quad Mesh Structure Improvement (" + std::string(quads ? "quads" : "triangles") + "): edge swaps " +
          std::to_string(r.swaps) + ", node eliminations " + std::to_string(r.eliminations) + ", edge divisions " +
          std::to_string(r.divisions) + "; passes " + std::to_string(r.passes) + "; elements " +
          std::to_string(pm.F.size()) + " -> " + std::to_string(r.mesh.F.size()) + "; worst " + q + " " + fmt(qb.min) +
          " -> " + fmt(qa.min) + ", mean " + q + " " + fmt(qb.mean) + " -> " + fmt(qa.mean) + "; time " +
          fmt(r.seconds, 3) + " s");
  ctx.log("Valence of interior nodes before: " + valenceLine(b.valence));
  ctx.log("Valence of interior nodes after: " + valenceLine(a.valence));
  auto& res = ctx.results();
  res.set("element_kind", quads ? "quads" : "triangles");
  res.set("edge_swaps", r.swaps);
  res.set("node_eliminations", r.eliminations);
  res.set("edge_divisions", r.divisions);
  res.set("passes", r.passes);
  res.set("elements_before", pm.F.size());
  res.set("elements_after", r.mesh.F.size());
  res.set("quality_min_before", qb.min);
  res.set("quality_min_after", qa.min);
  res.set("quality_mean_before", qb.mean);
  res.set("quality_mean_after", qa.mean);
  res.set("seconds", r.seconds);
}

void FilterQuadConvertPlugin::runSave(FilterContext& ctx) {
  MeshModel& mm = ctx.current();
  const std::string path = ctx.params().getSaveFileName("fileName").toStdString();
  const int f = ctx.enumIn("format", 3);
  pectus::requireMesh(mm.cm, {}, mm.label().toStdString());
  const auto pm = pq::fromCMesh(mm.cm, pectus::hasFauxEdges(mm.cm));
  pq::writePolyMesh(path, pm, f == 0 ? pq::PolyFormat::OBJ : f == 1 ? pq::PolyFormat::OFF : pq::PolyFormat::VTK);
  ctx.log("Pectus: Save Polygonal Mesh: wrote " + std::to_string(pm.V.size()) + " vertices, " + std::to_string(pm.quads()) +
          " quads, " + std::to_string(pm.triangles()) + " triangles to " + path);
  ctx.results().set("vertices", pm.V.size());
  ctx.results().set("quads", pm.quads());
  ctx.results().set("triangles", pm.triangles());
  ctx.results().set("file", path);
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterQuadConvertPlugin)
