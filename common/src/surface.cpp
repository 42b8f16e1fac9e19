#include "pectus/surface.h"

#include "pectus/union_find.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <utility>

namespace pectus {

namespace {
/// the first face with a vertex index out of range and that index (badFace stays -1 if none)
void findBadIndex(const Surface& m, int& badFace, int& badIndex) {
  const int nv = int(m.V.size()), nf = int(m.F.size());
  for (int f = 0; f < nf && badFace < 0; ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = m.F[std::size_t(f)][std::size_t(k)];
      if (i < 0 || i >= nv) {
        badFace = f;
        badIndex = i;
        break;
      }
    }
}

/// vertex -> faces (CSR)
void vertexFaces(const Surface& m, std::vector<int>& vfStart, std::vector<int>& vf) {
  const int nv = int(m.V.size()), nf = int(m.F.size());
  vfStart.assign(std::size_t(nv) + 1, 0);
  for (const auto& f : m.F)
    for (int k = 0; k < 3; ++k) ++vfStart[std::size_t(f[std::size_t(k)]) + 1];
  for (int i = 0; i < nv; ++i) vfStart[std::size_t(i) + 1] += vfStart[std::size_t(i)];
  vf.resize(std::size_t(vfStart[std::size_t(nv)]));
  std::vector<int> fill(vfStart.begin(), vfStart.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) vf[std::size_t(fill[std::size_t(m.F[std::size_t(f)][std::size_t(k)])]++)] = f;
}

/// the faces' local edges as (min, max, face*3 + local), sorted; local edge l is opposite local vertex l.
/// A face's repeated vertex is no edge: it is counted in collapsedEdges instead.
std::vector<std::pair<std::uint64_t, int>> sortedEdgeKeys(const Surface& m, std::vector<int>& collapsedEdges) {
  const int nf = int(m.F.size());
  std::vector<std::pair<std::uint64_t, int>> keys;
  keys.reserve(3 * std::size_t(nf));
  collapsedEdges.assign(m.V.size(), 0);
  for (int f = 0; f < nf; ++f)
    for (int l = 0; l < 3; ++l) {
      int a = m.F[std::size_t(f)][std::size_t((l + 1) % 3)], b = m.F[std::size_t(f)][std::size_t((l + 2) % 3)];
      if (a == b) {  // repeated vertex: the face is degenerate, the "edge" is a point
        ++collapsedEdges[std::size_t(a)];
        continue;
      }
      if (a > b) std::swap(a, b);
      keys.push_back({(std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b), f * 3 + l});
    }
  std::sort(keys.begin(), keys.end());
  return keys;
}

/// the edges from the sorted keys (one per run of equal keys), edge -> faces (CSR) and face -> edges
void buildEdges(const std::vector<std::pair<std::uint64_t, int>>& keys, std::size_t nf, Topology& t) {
  t.faceEdge.assign(nf, {-1, -1, -1});
  t.edgeFace.reserve(keys.size());
  t.edges.reserve(keys.size() / 2 + 1);  // a closed manifold has half as many edges as face corners
  t.edgeFaceStart.reserve(keys.size() / 2 + 2);
  t.edgeFaceStart.push_back(0);
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j].first == keys[i].first) ++j;
    Topology::Edge e;
    e.a = int(keys[i].first >> 32);
    e.b = int(keys[i].first & 0xffffffffu);
    e.f0 = keys[i].second;
    e.f1 = j - i >= 2 ? keys[i + 1].second : -1;
    e.faces = int(j - i);
    const int id = int(t.edges.size());
    for (std::size_t q = i; q < j; ++q) {
      t.faceEdge[std::size_t(keys[q].second / 3)][std::size_t(keys[q].second % 3)] = id;
      t.edgeFace.push_back(keys[q].second);
    }
    t.edgeFaceStart.push_back(int(t.edgeFace.size()));
    t.edges.push_back(e);
    i = j;
  }
}

/// Boundary and manifold vertices: a manifold fan is one cycle (edges = faces) or one chain (edges = faces + 1,
/// two boundary edges). Vertices of a face with a repeated vertex are not judged.
void judgeVertices(const Surface& m, Topology& t) {
  const int nv = int(m.V.size());
  t.boundary.assign(std::size_t(nv), 0);
  t.nonManifoldVertex.assign(std::size_t(nv), 0);
  std::vector<int> vEdges(std::size_t(nv), 0), vBnd(std::size_t(nv), 0);
  for (const auto& e : t.edges) {
    ++vEdges[std::size_t(e.a)];
    ++vEdges[std::size_t(e.b)];
    if (e.f1 < 0) { ++vBnd[std::size_t(e.a)]; ++vBnd[std::size_t(e.b)]; }
  }
  for (int i = 0; i < nv; ++i) {
    const std::size_t si = std::size_t(i);
    const int nfv = t.vfStart[si + 1] - t.vfStart[si];
    t.boundary[si] = vBnd[si] > 0;
    if (nfv == 0) continue;
    bool repeated = false;
    for (int q = t.vfStart[si]; q < t.vfStart[si + 1]; ++q) {
      const auto& F = m.F[std::size_t(t.vf[std::size_t(q)])];
      if (F[0] == F[1] || F[1] == F[2] || F[0] == F[2]) repeated = true;
    }
    if (repeated) continue;  // counted as degenerate, not judged here
    const bool ok = (vBnd[si] == 0 && vEdges[si] == nfv) || (vBnd[si] == 2 && vEdges[si] == nfv + 1);
    t.nonManifoldVertex[si] = !ok;
  }
}
}  // namespace

Topology::Topology(const Surface& m) {
  // 1. every index in range, or nothing else is built
  findBadIndex(m, badFace, badIndex);
  if (badFace >= 0) return;
  // 2. vertex -> faces
  vertexFaces(m, vfStart, vf);
  // 3. edges: one sort of the faces' local edges
  buildEdges(sortedEdgeKeys(m, collapsedEdges), m.F.size(), *this);
  // 4. boundary and manifold vertices, by counting
  judgeVertices(m, *this);
  // 5. fans around each vertex, by walking them
  countFans(m);
}

void Topology::countFans(const Surface& m) {
  const std::size_t nv = vfStart.size() - 1;
  fans.assign(nv, 0);
  // per vertex: its faces get local slots, joined (union-find) across every edge at the vertex
  std::vector<int> slot(m.F.size(), -1);
  UnionFind sets;
  for (std::size_t v = 0; v < nv; ++v) {
    sets.clear();
    for (int q = vfStart[v]; q < vfStart[v + 1]; ++q) {
      int& s = slot[std::size_t(vf[std::size_t(q)])];
      if (s < 0) s = sets.add();  // a face with a repeated vertex: one slot
    }
    for (int q = vfStart[v]; q < vfStart[v + 1]; ++q) {
      const int f = vf[std::size_t(q)];
      for (int l = 0; l < 3; ++l) {
        const int e = faceEdge[std::size_t(f)][std::size_t(l)];
        if (e < 0 || (edges[std::size_t(e)].a != int(v) && edges[std::size_t(e)].b != int(v))) continue;
        for (const int* g = edgeFacesBegin(e); g != edgeFacesEnd(e); ++g)
          sets.unite(slot[std::size_t(*g / 3)], slot[std::size_t(f)]);
      }
    }
    for (std::size_t i = 0; i < sets.size(); ++i) fans[v] += sets.isRoot(int(i));
    for (int q = vfStart[v]; q < vfStart[v + 1]; ++q) slot[std::size_t(vf[std::size_t(q)])] = -1;
  }
}

Topology::EdgeUse Topology::edgeUse() const {
  EdgeUse u;
  for (const auto& e : edges) u.once += e.faces == 1, u.moreThanTwice += e.faces > 2;
  for (int c : collapsedEdges) u.once += c == 1, u.moreThanTwice += c > 2;
  return u;
}

std::size_t Topology::boundaryEdges() const {
  return std::size_t(std::count_if(edges.begin(), edges.end(), [](const Edge& e) { return e.faces == 1; }));
}

std::size_t Topology::nonManifoldEdges() const {
  return std::size_t(std::count_if(edges.begin(), edges.end(), [](const Edge& e) { return e.faces > 2; }));
}

bool Topology::closedManifold() const {
  if (badFace >= 0 || edges.empty()) return false;
  for (const auto& e : edges)
    if (e.faces != 2) return false;
  return std::none_of(nonManifoldVertex.begin(), nonManifoldVertex.end(), [](char c) { return c != 0; });
}

int Topology::components(std::vector<int>& faceComponent) const {
  const int nf = int(faceEdge.size()), nv = int(boundary.size());
  UnionFind sets(boundary.size());
  // faces sharing a vertex are connected: union the vertices of each face
  std::vector<int> firstVertex(std::size_t(nf), -1);
  for (int v = 0; v < nv; ++v)
    for (int q = vfStart[std::size_t(v)]; q < vfStart[std::size_t(v) + 1]; ++q) {
      const int f = vf[std::size_t(q)];
      int& r = firstVertex[std::size_t(f)];
      if (r < 0) r = v;
      else sets.unite(v, r);
    }
  faceComponent.assign(std::size_t(nf), -1);
  std::vector<int> id(std::size_t(nv), -1);
  int n = 0;
  for (int f = 0; f < nf; ++f) {
    const int r = sets.find(firstVertex[std::size_t(f)]);
    if (id[std::size_t(r)] < 0) id[std::size_t(r)] = n++;
    faceComponent[std::size_t(f)] = id[std::size_t(r)];
  }
  return n;
}

}  // namespace pectus
