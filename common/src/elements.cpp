#include "pectus/elements.h"

#include <string>
#include <unordered_map>

#include "pectus/errors.h"
#include "pectus/surface.h"
#include "pectus/surface_cmesh.h"

namespace pectus {

namespace {

// The faces (Surface face indices, ascending, once per use) of the edge from corner k to corner k + 1 of
// face f. A collapsed edge (f has a repeated vertex there) is not an edge of the topology: it is held by
// every face with a collapsed edge at that vertex, as a table keyed by every local edge holds it.
std::vector<int> facesOfEdge(const Surface& s, const Topology& t, int f, int k) {
  std::vector<int> out;
  const int e = t.faceEdge[std::size_t(f)][std::size_t((k + 2) % 3)];  // local edge l is opposite corner l
  if (e >= 0) {
    for (const int* p = t.edgeFacesBegin(e); p != t.edgeFacesEnd(e); ++p) out.push_back(*p / 3);
    return out;
  }
  const int a = s.F[std::size_t(f)][std::size_t(k)];
  for (std::size_t g = 0; g < s.F.size(); ++g)
    for (int l = 0; l < 3; ++l)
      if (s.F[g][std::size_t((l + 1) % 3)] == a && s.F[g][std::size_t((l + 2) % 3)] == a) out.push_back(int(g));
  return out;
}

}  // namespace

std::size_t ElementMesh::quads() const {
  std::size_t n = 0;
  for (const auto& e : elements) n += (e.nv == 4);
  return n;
}
std::size_t ElementMesh::triangles() const { return elements.size() - quads(); }

bool hasFauxEdges(const CMeshO& m) {
  for (const auto& f : m.face)
    if (!f.IsD() && (f.IsF(0) || f.IsF(1) || f.IsF(2))) return true;
  return false;
}

ElementMesh buildElements(const CMeshO& m, ElementKind kind) {
  ElementMesh out;
  out.faceToElement.assign(m.face.size(), -1);
  const auto vi = [&m](const CFaceO& f, int k) { return int(vcg::tri::Index(m, f.cV(k))); };

  if (kind == ElementKind::Triangles) {
    for (std::size_t fi = 0; fi < m.face.size(); ++fi) {
      const auto& f = m.face[fi];
      if (f.IsD()) continue;
      Element e;
      e.nv = 3;
      for (int k = 0; k < 3; ++k) e.v[k] = vi(f, k);
      e.face[0] = int(fi);
      out.faceToElement[fi] = int(out.elements.size());
      out.elements.push_back(e);
    }
    return out;
  }

  // the live faces over every entry of m.vert (Surface vertex i is m.vert[i]), and back to m.face
  std::vector<int> faceOf, surfaceFace(m.face.size(), -1);
  const Surface s = surfaceOf(m, {SurfaceOf::Vertices::All}, nullptr, &faceOf);
  for (std::size_t i = 0; i < faceOf.size(); ++i) surfaceFace[std::size_t(faceOf[i])] = int(i);
  const Topology topo(s);
  for (std::size_t fi = 0; fi < m.face.size(); ++fi) {
    const auto& f = m.face[fi];
    if (f.IsD() || out.faceToElement[fi] >= 0) continue;
    int faux = -1, nfaux = 0;
    for (int k = 0; k < 3; ++k)
      if (f.IsF(k)) { faux = k; ++nfaux; }
    Element e;
    e.face[0] = int(fi);
    if (nfaux == 0) {
      e.nv = 3;
      for (int k = 0; k < 3; ++k) e.v[k] = vi(f, k);
    } else {
      if (nfaux > 1)
        throw TopologyError("face " + std::to_string(fi) + " has " + std::to_string(nfaux) +
                         " faux edges: the layer holds polygons with more than four sides, not quads");
      const int a = vi(f, faux), b = vi(f, (faux + 1) % 3), c = vi(f, (faux + 2) % 3);
      std::vector<int> nb = facesOfEdge(s, topo, surfaceFace[fi], faux);
      for (int& g : nb) g = faceOf[std::size_t(g)];
      if (nb.size() != 2)
        throw TopologyError("face " + std::to_string(fi) + " has a faux edge " +
                         (nb.size() < 2 ? std::string("on the boundary") : std::string("shared by more than two faces")) +
                         ": not a valid quad");
      const int gi = nb[0] == int(fi) ? nb[1] : nb[0];
      const auto& g = m.face[gi];
      int d = -1, gfaux = 0;
      for (int k = 0; k < 3; ++k) {
        const int w = vi(g, k);
        if (w != a && w != b) d = w;
        if (g.IsF(k)) ++gfaux;
      }
      if (d < 0 || gfaux != 1)
        throw TopologyError("faces " + std::to_string(fi) + " and " + std::to_string(gi) +
                         " do not form a quad (their faux edges do not match)");
      // f = (a,b,c) with faux edge a-b; g holds b-a and its far vertex d: boundary a, d, b, c
      e.nv = 4;
      e.v = {a, d, b, c};
      e.face[1] = gi;
      out.faceToElement[gi] = int(out.elements.size());
    }
    out.faceToElement[fi] = int(out.elements.size());
    out.elements.push_back(e);
  }
  return out;
}

}  // namespace pectus
