#include "pectus/mesh_checks.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <vector>

#include "pectus/edge_map.h"
#include "pectus/errors.h"

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

MeshReport inspectMesh(const CMeshO& m) {
  MeshReport r;
  std::vector<int> valence(m.vert.size(), 0);
  for (std::size_t i = 0; i < m.vert.size(); ++i) {
    const auto& v = m.vert[i];
    if (v.IsD()) continue;
    ++r.vertices;
    const auto& p = v.cP();
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) ++r.nonFiniteVertices;
  }
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    ++r.faces;
    for (int k = 0; k < 3; ++k) ++valence[vcg::tri::Index(m, f.cV(k))];
    const auto a = f.cP(0), b = f.cP(1), c = f.cP(2);
    const double area = double(((b - a) ^ (c - a)).Norm());
    if (f.cV(0) == f.cV(1) || f.cV(1) == f.cV(2) || f.cV(0) == f.cV(2) || !(area > 0.0)) ++r.degenerateFaces;
  }
  for (std::size_t i = 0; i < m.vert.size(); ++i)
    if (!m.vert[i].IsD() && valence[i] == 0) ++r.unreferencedVertices;
  {
    std::vector<std::array<std::size_t, 3>> tri;
    for (const auto& f : m.face) {
      if (f.IsD()) continue;
      std::array<std::size_t, 3> v{vcg::tri::Index(m, f.cV(0)), vcg::tri::Index(m, f.cV(1)), vcg::tri::Index(m, f.cV(2))};
      std::sort(v.begin(), v.end());
      tri.push_back(v);
    }
    std::sort(tri.begin(), tri.end());
    for (std::size_t i = 1; i < tri.size(); ++i)
      if (tri[i] == tri[i - 1]) ++r.duplicateFaces;
  }

  const EdgeMap edges(m);
  // per vertex: count of incident boundary edges and of faces, to detect non-manifold vertices
  // (a manifold vertex's fan is one cycle: #edges-in-fan == #faces, or a chain with 2 boundary edges)
  std::vector<int> vBoundary(m.vert.size(), 0), vEdges(m.vert.size(), 0);
  edges.forEach([&](int a, int b, const EdgeMap::Faces& fs) {
    if (fs.size() == 1) { ++r.boundaryEdges; ++vBoundary[a]; ++vBoundary[b]; }
    if (fs.size() > 2) ++r.nonManifoldEdges;
    ++vEdges[a];
    ++vEdges[b];
  });
  // Euler check on each vertex star: for a single disk, edges = faces (closed fan) or faces + 1 (open fan).
  // Two fans glued at the vertex give more edges than faces + 1, or more than two boundary edges.
  for (std::size_t i = 0; i < m.vert.size(); ++i) {
    if (m.vert[i].IsD() || valence[i] == 0) continue;
    const int fcount = valence[i];
    const bool ok = (vBoundary[i] == 0 && vEdges[i] == fcount) || (vBoundary[i] == 2 && vEdges[i] == fcount + 1);
    if (!ok) ++r.nonManifoldVertices;
  }
  return r;
}

MeshReport requireMesh(const CMeshO& m, const MeshRequirements& req, const std::string& layer) {
  MeshReport r = inspectMesh(m);
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
