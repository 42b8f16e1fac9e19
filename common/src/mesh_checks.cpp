#include "pectus/mesh_checks.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <vector>

#include "pectus/errors.h"
#include "pectus/surface.h"
#include "pectus/surface_cmesh.h"

namespace pectus {

std::string MeshReport::summary() const {
  std::ostringstream s;
  s << vertices << " vertices, " << faces << " faces";
  if (boundaryEdges) s << ", " << boundaryEdges << " boundary edges";
  if (nonManifoldEdges) s << ", " << nonManifoldEdges << " non-manifold edges";
  if (nonManifoldVertices) s << ", " << nonManifoldVertices << " non-manifold vertices";
  if (degenerateFaces) s << ", " << degenerateFaces << " degenerate faces";
  if (duplicateFaces) s << ", " << duplicateFaces << " duplicate faces";
  if (nonFiniteVertices) s << ", " << nonFiniteVertices << " vertices with NaN/Inf coordinates";
  return s.str();
}

namespace {

// Live vertices and those with NaN/Inf coordinates.
void countVertices(const CMeshO& m, MeshReport& r) {
  for (const auto& v : m.vert) {
    if (v.IsD()) continue;
    ++r.vertices;
    const auto& p = v.cP();
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) ++r.nonFiniteVertices;
  }
}

// Live faces and the degenerate ones (a repeated vertex, or no area in the mesh's own precision).
void countFaces(const CMeshO& m, MeshReport& r) {
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    ++r.faces;
    const auto a = f.cP(0), b = f.cP(1), c = f.cP(2);
    const double area = double(((b - a) ^ (c - a)).Norm());
    if (f.cV(0) == f.cV(1) || f.cV(1) == f.cV(2) || f.cV(0) == f.cV(2) || !(area > 0.0)) ++r.degenerateFaces;
  }
}

// Faces with the same three vertices as an earlier face, in any order.
std::size_t duplicateFaces(const Surface& s) {
  std::vector<std::array<int, 3>> tri(s.F);
  for (auto& t : tri) std::sort(t.begin(), t.end());
  std::sort(tri.begin(), tri.end());
  std::size_t n = 0;
  for (std::size_t i = 1; i < tri.size(); ++i) n += tri[i] == tri[i - 1];
  return n;
}

// The vertex test of the checks, by counting on each vertex's star: one disk has as many edges as faces
// (a closed fan) or one more, two of them boundary edges (an open fan). A collapsed edge of a degenerate
// face counts as an edge (v, v), twice at v, a boundary edge when no other face collapses there. The count
// misses a closed fan touching another fan (Topology::fans sees it); the filters accept what it accepts.
std::vector<char> countTestNonManifold(const Topology& t) {
  const std::size_t nv = t.boundary.size();
  std::vector<int> vEdges(nv, 0), vBoundary(nv, 0);
  for (const auto& e : t.edges) {
    ++vEdges[std::size_t(e.a)], ++vEdges[std::size_t(e.b)];
    if (e.faces == 1) ++vBoundary[std::size_t(e.a)], ++vBoundary[std::size_t(e.b)];
  }
  for (std::size_t v = 0; v < nv; ++v)
    if (const int c = t.collapsedEdges[v]) vEdges[v] += 2, vBoundary[v] += c == 1 ? 2 : 0;
  std::vector<char> bad(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    const int faces = t.vfStart[v + 1] - t.vfStart[v];  // a face once per corner at v
    bad[v] = !((vBoundary[v] == 0 && vEdges[v] == faces) || (vBoundary[v] == 2 && vEdges[v] == faces + 1));
  }
  return bad;
}

// Duplicate faces, boundary and non-manifold edges, unreferenced and non-manifold vertices: the part of
// the inspection that needs the mesh's topology (an edge sort, the largest cost of the checks).
void inspectTopology(const CMeshO& m, MeshReport& r) {
  // the live faces over every entry of m.vert: Surface vertex i is m.vert[i]
  const Surface s = surfaceOf(m, {SurfaceOf::Vertices::All});
  const Topology t(s);
  r.duplicateFaces = duplicateFaces(s);
  const Topology::EdgeUse use = t.edgeUse();
  r.boundaryEdges = use.once;
  r.nonManifoldEdges = use.moreThanTwice;
  const std::vector<char> bad = countTestNonManifold(t);
  for (std::size_t i = 0; i < m.vert.size(); ++i) {
    if (m.vert[i].IsD()) continue;
    const bool used = t.vfStart[i + 1] > t.vfStart[i];
    r.unreferencedVertices += !used;
    r.nonManifoldVertices += used && bad[i];
  }
}

}  // namespace

MeshReport inspectMesh(const CMeshO& m) {
  MeshReport r;
  countVertices(m, r);
  countFaces(m, r);
  inspectTopology(m, r);
  return r;
}

MeshReport requireMesh(const CMeshO& m, const MeshRequirements& req, const std::string& layer) {
  MeshReport r;
  countVertices(m, r);
  countFaces(m, r);
  if (req.edgeManifold || req.vertexManifold || req.closed) inspectTopology(m, r);
  const std::string L = "layer '" + layer + "': ";
  if (req.faces && r.vertices == 0) throw TopologyError(L + "the layer is empty (no vertices)");
  if (req.faces && r.faces == 0)
    throw TopologyError(L + "the layer has " + std::to_string(r.vertices) + " vertices but no faces (a point cloud); a surface mesh is needed");
  if (req.finite && r.nonFiniteVertices)
    throw InputError(L + std::to_string(r.nonFiniteVertices) + " vertices have NaN or infinite coordinates; remove them first");
  if (req.edgeManifold && r.duplicateFaces)
    throw TopologyError(L + std::to_string(r.duplicateFaces) +
                     " duplicate faces (the same three vertices as another face); run 'Remove Duplicate Faces' first");
  if (req.edgeManifold && r.nonManifoldEdges)
    throw TopologyError(L + std::to_string(r.nonManifoldEdges) +
                     " non-manifold edges (shared by three or more faces); run 'Repair non Manifold Edges' first");
  if (req.vertexManifold && r.nonManifoldVertices)
    throw TopologyError(L + std::to_string(r.nonManifoldVertices) +
                     " non-manifold vertices; run 'Repair non Manifold Vertices by splitting' first");
  if (req.noDegenerate && r.degenerateFaces)
    throw TopologyError(L + std::to_string(r.degenerateFaces) + " zero-area faces; run 'Remove Zero Area Faces' first");
  if (req.closed && r.boundaryEdges)
    throw TopologyError(L + "the surface is open (" + std::to_string(r.boundaryEdges) + " boundary edges); a closed (watertight) surface is needed");
  return r;
}

}  // namespace pectus
