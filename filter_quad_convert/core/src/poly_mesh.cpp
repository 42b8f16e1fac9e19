#include "pectus/quad/poly_mesh.h"

#include <algorithm>
#include <cstdint>
#include <iomanip>
#include <sstream>
#include <unordered_map>

#include <vcg/complex/complex.h>

#include "pectus/elements.h"
#include "pectus/errors.h"

namespace pectus::quad {

std::size_t PolyMesh::quads() const {
  std::size_t n = 0;
  for (const auto& f : F) n += f.nv == 4;
  return n;
}

double polyQuality(const PolyMesh& m, const Poly& p) {
  const auto& X = m.V;
  return p.nv == 4 ? quadBeta(X[p.v[0]], X[p.v[1]], X[p.v[2]], X[p.v[3]]) : triangleAlpha(X[p.v[0]], X[p.v[1]], X[p.v[2]]);
}

void requireFiniteVertices(const std::vector<Vec3>& V) {
  for (std::size_t i = 0; i < V.size(); ++i)
    if (!V[i].allFinite())
      throw InputError("vertex " + std::to_string(i) + " has a NaN or infinite coordinate; remove it first (unused "
                       "vertices too)");
}

void requireElementIndices(const char* kind, std::size_t index, const int* v, int nv, std::size_t vertices) {
  const std::string what = std::string(kind) + " " + std::to_string(index);
  for (int k = 0; k < nv; ++k) {
    if (v[k] < 0 || std::size_t(v[k]) >= vertices)
      throw TopologyError(what + " uses vertex index " + std::to_string(v[k]) + ", out of range");
    for (int l = 0; l < k; ++l)
      if (v[k] == v[l]) throw TopologyError(what + " uses a vertex twice (a collapsed face); remove it first");
  }
}

void requirePolyMesh(const PolyMesh& m) {
  requireFiniteVertices(m.V);
  for (std::size_t f = 0; f < m.F.size(); ++f) {
    if (m.F[f].nv != 3 && m.F[f].nv != 4)
      throw TopologyError("element " + std::to_string(f) + " has " + std::to_string(m.F[f].nv) +
                       " vertices; only triangles and quads are supported");
    requireElementIndices("element", f, m.F[f].v.data(), m.F[f].nv, m.V.size());
  }
}

void valences(const PolyMesh& m, std::vector<int>& valence, std::vector<char>& boundary) {
  valence.assign(m.V.size(), 0);
  boundary.assign(m.V.size(), 0);
  std::unordered_map<std::uint64_t, int> edgeCount;
  edgeCount.reserve(m.F.size() * 4);
  for (const auto& f : m.F)
    for (int k = 0; k < f.nv; ++k) {
      ++valence[f.v[k]];
      std::uint32_t a = f.v[k], b = f.v[(k + 1) % f.nv];
      if (a > b) std::swap(a, b);
      ++edgeCount[(std::uint64_t(a) << 32) | b];
    }
  for (const auto& kv : edgeCount)
    if (kv.second == 1) boundary[kv.first >> 32] = boundary[kv.first & 0xffffffffu] = 1;
}

PolyStats polyStats(const PolyMesh& m) {
  PolyStats s;
  std::vector<double> b, a;
  for (const auto& f : m.F) (f.nv == 4 ? b : a).push_back(polyQuality(m, f));
  s.quads = b.size();
  s.triangles = a.size();
  s.quadPercent = m.F.empty() ? 0 : 100.0 * double(s.quads) / double(m.F.size());
  s.beta = summarizeQuality(b);
  s.alpha = summarizeQuality(a);
  s.invalidQuads = s.beta.invalid;
  std::vector<int> val;
  std::vector<char> bnd;
  valences(m, val, bnd);
  s.valence.assign(13, 0);
  for (std::size_t i = 0; i < val.size(); ++i)
    if (!bnd[i] && val[i] > 0) ++s.valence[std::min(val[i], 12)];
  return s;
}

std::string PolyStats::summary() const {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(4);
  o << quads << " quads, " << triangles << " triangles (" << std::setprecision(1) << quadPercent << "% quads)";
  o.precision(4);
  if (quads) o << "; beta min " << beta.min << " mean " << beta.mean << "; invalid quads (beta <= 0): " << invalidQuads;
  if (triangles) o << "; triangle alpha min " << alpha.min << " mean " << alpha.mean;
  return o.str();
}

PolyMesh fromCMesh(const CMeshO& m, bool quads, std::vector<int>* vertexIndex) {
  PolyMesh p;
  const std::vector<int> map = liveVertices(m, p.V, vertexIndex);
  const ElementMesh em = buildElements(m, quads ? ElementKind::Quads : ElementKind::Triangles);
  p.F.reserve(em.elements.size());
  for (const auto& e : em.elements) {
    Poly q;
    q.nv = e.nv;
    for (int k = 0; k < e.nv; ++k) q.v[k] = map[e.v[k]];
    // buildElements gives a, d, b, c with faux edge a-b = v0-v2: the stored diagonal is kept
    p.F.push_back(q);
  }
  return p;
}

void toCMesh(const PolyMesh& p, CMeshO& m) {
  // A faux diagonal must be an edge of no other face, or MeshLab (and buildElements) would see a polygon of
  // more than four sides: where v0-v2 is taken (e.g. two quads around a node of valence 2), use v1-v3.
  std::unordered_map<std::uint64_t, int> used;
  const auto key = [](int a, int b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
  };
  for (const auto& q : p.F)
    for (int k = 0; k < q.nv; ++k) ++used[key(q.v[k], q.v[(k + 1) % q.nv])];
  m.Clear();
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m, p.V.size());
  for (std::size_t i = 0; i < p.V.size(); ++i, ++vi) vi->P() = toPoint(p.V[i]);
  const std::size_t nf = p.F.size() + p.quads();
  vcg::tri::Allocator<CMeshO>::AddFaces(m, nf);
  std::size_t k = 0;
  for (Poly q : p.F) {
    if (q.nv == 4) {
      if (used.count(key(q.v[0], q.v[2])) && !used.count(key(q.v[1], q.v[3]))) q.v = {q.v[1], q.v[2], q.v[3], q.v[0]};
      ++used[key(q.v[0], q.v[2])];
    }
    auto& f = m.face[k++];
    f.ClearF(0); f.ClearF(1); f.ClearF(2);
    for (int j = 0; j < 3; ++j) f.V(j) = &m.vert[q.v[j]];
    if (q.nv == 4) {
      f.SetF(2);  // edge v2-v0
      auto& g = m.face[k++];
      g.ClearF(0); g.ClearF(1); g.ClearF(2);
      g.V(0) = &m.vert[q.v[0]];
      g.V(1) = &m.vert[q.v[2]];
      g.V(2) = &m.vert[q.v[3]];
      g.SetF(0);  // edge v0-v2
    }
  }
}

void chooseDiagonal(const PolyMesh& m, Poly& q) {
  if (q.nv != 4) return;
  const auto& X = m.V;
  const auto& v = q.v;
  const double d02 = std::min(triangleAlpha(X[v[0]], X[v[1]], X[v[2]]), triangleAlpha(X[v[0]], X[v[2]], X[v[3]]));
  const double d13 = std::min(triangleAlpha(X[v[1]], X[v[2]], X[v[3]]), triangleAlpha(X[v[1]], X[v[3]], X[v[0]]));
  if (d13 > d02) q.v = {v[1], v[2], v[3], v[0]};
}

}  // namespace pectus::quad
