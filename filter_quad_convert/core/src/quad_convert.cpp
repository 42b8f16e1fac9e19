#include "pectus/quad/quad_convert.h"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>

#include "pectus/quad/matching.h"
#include "pectus/errors.h"

namespace pectus::quad {

namespace {
std::uint64_t edgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}
Vec3 triNormal(const c1::TriMesh& m, const std::array<int, 3>& t) {
  const Vec3 n = (m.V[t[1]] - m.V[t[0]]).cross(m.V[t[2]] - m.V[t[0]]);
  const double l = n.norm();
  return l > 0 ? Vec3(n / l) : Vec3::Zero();
}
}  // namespace

std::vector<Candidate> quadCandidates(const c1::TriMesh& tri, const ConvertOptions& o) {
  const Topology topo(tri);
  if (topo.badFace >= 0) throw TopologyError("face " + std::to_string(topo.badFace) + " uses vertex index " +
                                          std::to_string(topo.badIndex) + ", but the mesh has " +
                                          std::to_string(tri.V.size()) + " vertices");
  const double cosMax = std::cos(o.maxDihedralDeg * M_PI / 180.0);
  const double minQ = std::max(0.0, o.minQuality);
  std::vector<Candidate> out;
  for (int f = 0; f < int(tri.F.size()); ++f) {
    const auto& t = tri.F[f];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      const int id = topo.faceEdge[std::size_t(f)][std::size_t((k + 2) % 3)];  // edge (a, b): opposite corner k + 2
      if (id < 0 || topo.edges[std::size_t(id)].faces != 2) continue;
      const int g0 = topo.edges[std::size_t(id)].f0 / 3, g1 = topo.edges[std::size_t(id)].f1 / 3;
      const int g = g0 == f ? g1 : g0;
      if (g <= f) continue;  // each pair once
      const auto& u = tri.F[g];
      int d = -1;
      bool consistent = false;
      for (int j = 0; j < 3; ++j) {
        if (u[j] != a && u[j] != b) d = u[j];
        if (u[j] == b && u[(j + 1) % 3] == a) consistent = true;
      }
      if (d < 0 || d == c || !consistent) continue;
      const Vec3 n0 = triNormal(tri, t), n1 = triNormal(tri, u);
      if (n0.isZero() || n1.isZero() || n0.dot(n1) < cosMax) continue;
      const Vec3 n = (n0 + n1).normalized();
      const auto& X = tri.V;
      const double beta = std::min(quadBeta(X[a], X[d], X[b], X[c]), quadBetaWithNormal(X[a], X[d], X[b], X[c], n));
      if (!(beta > minQ)) continue;
      out.push_back({f, g, {a, d, b, c}, beta});
    }
  }
  return out;
}

PolyMesh splitToQuads(const PolyMesh& m, const PlaceFn& place, std::size_t* newNodes) {
  PolyMesh out;
  out.V = m.V;
  std::vector<Vec3> linear;  // straight-line position of every new node
  std::unordered_map<std::uint64_t, int> mid;
  mid.reserve(m.F.size() * 2);
  const auto addNode = [&](const Vec3& p) {
    linear.push_back(p);
    out.V.push_back(place(p));
    return int(out.V.size()) - 1;
  };
  const auto midpoint = [&](int a, int b) {
    auto it = mid.find(edgeKey(a, b));
    if (it != mid.end()) return it->second;
    const int i = addNode(0.5 * (m.V[a] + m.V[b]));
    mid.emplace(edgeKey(a, b), i);
    return i;
  };
  out.F.reserve(m.F.size() * 4);
  for (const auto& f : m.F) {
    Vec3 c = Vec3::Zero();
    for (int k = 0; k < f.nv; ++k) c += m.V[f.v[k]];
    const int ci = addNode(c / f.nv);
    std::array<int, 4> mids{};
    for (int k = 0; k < f.nv; ++k) mids[k] = midpoint(f.v[k], f.v[(k + 1) % f.nv]);
    for (int k = 0; k < f.nv; ++k) {
      Poly q;
      q.nv = 4;
      q.v = {f.v[k], mids[k], ci, mids[(k + f.nv - 1) % f.nv]};
      out.F.push_back(q);
    }
  }
  // A sub-quad of a convex element is convex in the element's own (bilinear / affine) parametrisation; where
  // placing its new nodes on the surface makes it non-convex (strong curvature, poor elements), those nodes
  // go back to their straight-line positions.
  const int n0 = int(m.V.size());
  for (int round = 0; round < 3; ++round) {
    bool changed = false;
    for (const auto& q : out.F) {
      if (polyQuality(out, q) > 0) continue;
      for (int k = 0; k < 4; ++k)
        if (q.v[k] >= n0 && out.V[q.v[k]] != linear[q.v[k] - n0]) {
          out.V[q.v[k]] = linear[q.v[k] - n0];
          changed = true;
        }
    }
    if (!changed) break;
  }
  for (auto& q : out.F) chooseDiagonal(out, q);
  if (newNodes) *newNodes = out.V.size() - m.V.size();
  return out;
}

ConvertResult convertToQuads(const c1::TriMesh& tri, const ConvertOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  if (tri.F.empty()) throw TopologyError("the mesh has no triangle to convert");
  // (unchecked, a NaN vertex, used or not, would go through into the output, a bad index would be read out
  // of range, and a triangle with a repeated vertex would go through as a leftover element with that vertex
  // twice)
  requireFiniteVertices(tri.V);
  for (std::size_t f = 0; f < tri.F.size(); ++f) requireElementIndices("triangle", f, tri.F[f].data(), 3, tri.V.size());
  ConvertResult r;
  const auto cand = quadCandidates(tri, o);
  r.candidates = cand.size();
  if (cand.empty())
    throw TopologyError("no two adjacent triangles make an acceptable quad (isolated triangles, inconsistent "
                     "orientation, every pair beyond the dihedral limit or below the minimum quality): nothing to convert");
  std::vector<WeightedEdge> edges;
  edges.reserve(cand.size());
  for (const auto& c : cand) edges.push_back({c.t0, c.t1, c.beta});
  const int n = int(tri.F.size());
  const std::vector<int> mate =
      o.pairing == Pairing::Greedy ? greedyMatching(n, edges) : maxWeightMatching(n, edges, true);

  std::unordered_map<std::uint64_t, std::size_t> candOf;
  for (std::size_t i = 0; i < cand.size(); ++i) candOf[edgeKey(cand[i].t0, cand[i].t1)] = i;
  PolyMesh pm;
  pm.V = tri.V;
  pm.F.reserve(tri.F.size());
  for (int f = 0; f < n; ++f) {
    Poly p;
    if (mate[f] < 0) {
      p.nv = 3;
      for (int k = 0; k < 3; ++k) p.v[k] = tri.F[f][k];
      ++r.leftoverTriangles;
    } else if (mate[f] > f) {
      const auto& c = cand[candOf.at(edgeKey(f, mate[f]))];
      p.nv = 4;
      p.v = c.quad;  // diagonal v0-v2 = the shared edge: MeshLab's faces are the input triangles
      r.totalBeta += c.beta;
      ++r.merged;
    } else {
      continue;
    }
    pm.F.push_back(p);
  }

  if (o.leftovers == Leftovers::AllQuads && r.leftoverTriangles > 0) {
    c1::C1Surface surface(tri);  // VertexNormal frame: any oriented 2-manifold
    surface.buildIndex();
    pm = splitToQuads(pm, [&surface](const Vec3& p) { return surface.closestPoint(p).point; }, &r.newNodes);
    r.subdivided = true;
  }
  r.mesh = std::move(pm);
  r.stats = polyStats(r.mesh);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace pectus::quad
