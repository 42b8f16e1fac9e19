#include "pectus/smooth/creases.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <unordered_map>

#include "pectus/errors.h"
#include "pectus/surface.h"

namespace pectus::smooth {

namespace {

struct Edge {
  int a, b;          ///< a < b
  int f0 = -1, f1 = -1;
  int faces = 0;
  double dihedral = 0;  ///< degrees, 0 unless the edge has two faces with normals
};

// The mesh's edges with their faces and dihedral angles, and each face's three edges (faceEdges[f][k]: from
// corner k to k + 1). Edges are numbered in the order the faces (then their corners) first use them, which
// is the order the chains grow in. A degenerate face's collapsed edge (a repeated vertex) is an edge (v, v)
// here, one per vertex; it is never sharp (a degenerate face has no normal).
struct EdgeTable {
  std::vector<Edge> E;
  std::vector<std::array<int, 3>> faceEdges;

  EdgeTable(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& F, const Topology& topo)
      : faceEdges(F.size()) {
    if (topo.badFace >= 0)
      throw InternalError("crease detection: face " + std::to_string(topo.badFace) + " uses vertex index " +
                          std::to_string(topo.badIndex) + " of " + std::to_string(V.size()));
    if (topo.vfStart.size() != V.size() + 1 || topo.faceEdge.size() != F.size())
      throw InternalError("crease detection: the topology given is not that of the mesh given");
    number(V.size(), F, topo);
    for (auto& e : E) {
      if (e.faces != 2) continue;
      const Vec3 a = unitNormal(V, F[std::size_t(e.f0)]), b = unitNormal(V, F[std::size_t(e.f1)]);
      if (a.squaredNorm() > 0 && b.squaredNorm() > 0) e.dihedral = std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180.0 / M_PI;
    }
  }
  // the unit normal of face f, zero if it has none
  static Vec3 unitNormal(const std::vector<Vec3>& V, const std::array<int, 3>& f) {
    const Vec3 n = (V[std::size_t(f[1])] - V[std::size_t(f[0])]).cross(V[std::size_t(f[2])] - V[std::size_t(f[0])]);
    return n.norm() > 0 && n.allFinite() ? Vec3(n.normalized()) : Vec3::Zero();
  }
  // E in first-use order from the topology's edges; f0 the first face of an edge, f1 its last other one
  void number(std::size_t nv, const std::vector<std::array<int, 3>>& F, const Topology& topo) {
    std::vector<int> ofEdge(topo.edges.size(), -1), ofCollapsed(nv, -1);
    for (std::size_t f = 0; f < F.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int e = topo.faceEdge[f][std::size_t((k + 2) % 3)];  // local edge l is opposite corner l
        const int a = F[f][std::size_t(k)];
        int& id = e >= 0 ? ofEdge[std::size_t(e)] : ofCollapsed[std::size_t(a)];
        if (id < 0) {
          id = int(E.size());
          E.push_back(e >= 0 ? fromTopology(topo, e) : Edge{a, a});
        }
        if (e < 0) {  // a collapsed edge: its faces counted here, in face order
          Edge& c = E[std::size_t(id)];
          (c.faces == 0 ? c.f0 : c.f1) = int(f);
          ++c.faces;
        }
        faceEdges[f][std::size_t(k)] = id;
      }
  }
  static Edge fromTopology(const Topology& topo, int e) {
    const Topology::Edge& t = topo.edges[std::size_t(e)];
    Edge out{t.a, t.b};
    out.faces = t.faces;
    out.f0 = t.f0 / 3;
    if (t.faces >= 2) out.f1 = *(topo.edgeFacesEnd(e) - 1) / 3;
    return out;
  }
  double dihedral(int i) const { return E[std::size_t(i)].dihedral; }
  // the wings of edge i: the other edges of its two faces
  void wingsOf(std::size_t i, std::vector<int>& w) const {
    w.clear();
    for (int f : {E[i].f0, E[i].f1})
      for (int j : faceEdges[std::size_t(f)])
        if (std::size_t(j) != i) w.push_back(j);
  }
};

// an edge whose key is in `ignored` (sorted) is never sharp
bool isIgnored(const std::vector<std::uint64_t>& ignored, const Edge& e) {
  return std::binary_search(ignored.begin(), ignored.end(), edgeKey(e.a, e.b));
}

// 1. sharp across: bent at least minDihedral, and edgeProminence times the median of its wings that are
// not bent beyond minDihedral (of all of them if all are): the bending of the surface beside the edge
std::vector<char> sharpEdges(const EdgeTable& T, const std::vector<std::uint64_t>& ignored, const CreaseOptions& opt) {
  const auto& E = T.E;
  std::vector<char> bent(E.size(), 0), sharp(E.size(), 0);
  for (std::size_t i = 0; i < E.size(); ++i)
    bent[i] = E[i].faces == 2 && E[i].dihedral >= opt.minDihedralDeg && !isIgnored(ignored, E[i]);
  std::vector<int> w;
  std::vector<double> wd;
  for (std::size_t i = 0; i < E.size(); ++i) {
    if (!bent[i]) continue;
    T.wingsOf(i, w);
    wd.clear();
    for (int j : w)
      if (!bent[std::size_t(j)]) wd.push_back(T.dihedral(j));
    if (wd.empty())
      for (int j : w) wd.push_back(T.dihedral(j));
    std::sort(wd.begin(), wd.end());
    const std::size_t k = wd.size();
    const double median = k % 2 ? wd[k / 2] : 0.5 * (wd[k / 2 - 1] + wd[k / 2]);
    sharp[i] = E[i].dihedral >= opt.edgeProminence * median;
  }
  return sharp;
}

// per sharp edge, the mean dihedral of its smooth wings: those that are not sharp themselves (all of them
// if every one is); 0 for the other edges
std::vector<double> smoothWings(const EdgeTable& T, const std::vector<char>& sharp) {
  std::vector<double> wing(T.E.size(), 0.0);
  std::vector<int> w;
  for (std::size_t i = 0; i < T.E.size(); ++i) {
    if (!sharp[i]) continue;
    T.wingsOf(i, w);
    double sum = 0, all = 0;
    int n = 0;
    for (int j : w) {
      all += T.dihedral(j);
      if (!sharp[std::size_t(j)]) sum += T.dihedral(j), ++n;
    }
    wing[i] = n ? sum / n : all / double(std::max<std::size_t>(w.size(), 1));
  }
  return wing;
}

// the mesh's noise level: the median dihedral angle of its inner edges that are not sharp (the fandisk:
// 0 degrees; the bunny: 3; the CT femur: 9)
double noiseLevel(const EdgeTable& T, const std::vector<std::uint64_t>& ignored, const std::vector<char>& sharp) {
  std::vector<double> d;
  for (std::size_t i = 0; i < T.E.size(); ++i) {
    const Edge& e = T.E[i];
    if (e.faces == 2 && !isIgnored(ignored, e) && !sharp[i]) d.push_back(e.dihedral);
  }
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// 2. chains: two sharp edges through a node are linked if each is the other's straightest continuation
// there (dihedral angles within linkRatio, turning at most maxTurn); a chain is a connected set of links
std::vector<std::vector<int>> linkChains(const std::vector<Vec3>& V, const EdgeTable& T, const std::vector<char>& sharp,
                                         const std::vector<std::vector<int>>& nodeSharp, const CreaseOptions& opt) {
  const auto& E = T.E;
  const double cosTurn = std::cos(opt.maxTurnDeg * M_PI / 180.0);
  // the turn of the chain i -> j at v (cosine of the angle between i's direction into v and j's out of
  // it; 1 straight on), or -2 if they may not link (dihedral angles too different)
  auto straightness = [&](int v, int i, int j) {
    const Edge& ei = E[std::size_t(i)];
    const Edge& ej = E[std::size_t(j)];
    const double r = ei.dihedral / ej.dihedral;
    if (r > opt.linkRatio || r < 1.0 / opt.linkRatio) return -2.0;
    const Vec3 di = V[std::size_t(ei.a == v ? ei.b : ei.a)] - V[std::size_t(v)];
    const Vec3 dj = V[std::size_t(ej.a == v ? ej.b : ej.a)] - V[std::size_t(v)];
    const double len = di.norm() * dj.norm();
    return len > 0 ? -di.dot(dj) / len : -2.0;
  };
  // i's continuation at v: the sharp edge through v that goes on most straight, turning at most maxTurn
  auto continuation = [&](int v, int i) {
    int best = -1;
    double bestS = cosTurn;
    for (int j : nodeSharp[std::size_t(v)]) {
      if (j == i) continue;
      const double st = straightness(v, i, j);
      if (st >= bestS) bestS = st, best = j;
    }
    return best;
  };
  // linked: each is the other's continuation (a spur of noise at a crease node does not break the crease)
  auto linked = [&](int v, int i, int j) { return continuation(v, i) == j && continuation(v, j) == i; };
  std::vector<int> chainOf(E.size(), -1);
  std::vector<std::vector<int>> chains;
  for (std::size_t s = 0; s < E.size(); ++s) {
    if (!sharp[s] || chainOf[s] >= 0) continue;
    const int c = int(chains.size());
    chains.emplace_back();
    std::vector<int> stack{int(s)};
    chainOf[s] = c;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      chains.back().push_back(i);
      for (int v : {E[std::size_t(i)].a, E[std::size_t(i)].b})
        for (int j : nodeSharp[std::size_t(v)])
          if (chainOf[std::size_t(j)] < 0 && linked(v, i, j)) {
            chainOf[std::size_t(j)] = c;
            stack.push_back(j);
          }
    }
  }
  return chains;
}

// 3a. consistent: little variation along the chain, sharper than its wings and than the mesh's noise
std::vector<char> consistentChains(const EdgeTable& T, const std::vector<std::vector<int>>& chains, const std::vector<double>& wing,
                                   double noise, const CreaseOptions& opt) {
  std::vector<char> consistent(chains.size(), 0);
  for (std::size_t c = 0; c < chains.size(); ++c) {
    double sum = 0, sum2 = 0, w = 0;
    for (int i : chains[c]) {
      const double d = T.dihedral(i);
      sum += d, sum2 += d * d, w += wing[std::size_t(i)];
    }
    const double n = double(chains[c].size()), mean = sum / n;
    const double sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    consistent[c] = sd <= opt.maxVariation * mean && mean >= opt.chainProminence * (w / n) && mean >= opt.noiseProminence * noise;
  }
  return consistent;
}

// 3b. structural: long, or from corner to corner (a corner: a node where three or more consistent chains
// end, and no other sharp edge)
std::vector<char> structuralChains(const EdgeTable& T, const std::vector<std::vector<int>>& chains, const std::vector<char>& consistent,
                                   const std::vector<std::vector<int>>& nodeSharp, const CreaseOptions& opt) {
  std::vector<int> consistentEnds(nodeSharp.size(), 0);
  std::vector<std::vector<int>> ends(chains.size());
  for (std::size_t c = 0; c < chains.size(); ++c) {
    std::unordered_map<int, int> deg;
    for (int i : chains[c]) ++deg[T.E[std::size_t(i)].a], ++deg[T.E[std::size_t(i)].b];
    for (const auto& [v, k] : deg)
      if (k == 1) ends[c].push_back(v);
    if (consistent[c])
      for (int v : ends[c]) ++consistentEnds[std::size_t(v)];
  }
  std::vector<char> structural(chains.size(), 0);
  for (std::size_t c = 0; c < chains.size(); ++c) {
    bool cornerToCorner = !ends[c].empty();
    for (int v : ends[c])
      cornerToCorner = cornerToCorner && consistentEnds[std::size_t(v)] >= 3 &&
                       consistentEnds[std::size_t(v)] == int(nodeSharp[std::size_t(v)].size());
    structural[c] = int(chains[c].size()) >= opt.minChainEdges || cornerToCorner;
  }
  return structural;
}

// 3c. short consistent chains that continue a crease (meet one of its ends) are creases too, and so on along
// a crease that fades out in steps
void growAlongCreases(const EdgeTable& T, const std::vector<std::vector<int>>& chains, const std::vector<char>& consistent,
                      std::size_t nv, std::vector<char>& crease) {
  for (bool grew = true; grew;) {
    grew = false;
    std::vector<char> end(nv, 0);
    for (std::size_t c = 0; c < chains.size(); ++c)
      if (crease[c])
        for (int i : chains[c])
          for (int v : {T.E[std::size_t(i)].a, T.E[std::size_t(i)].b}) end[std::size_t(v)] ^= 1;  // odd degree: an end
    std::vector<char> grown(chains.size(), 0);
    for (std::size_t c = 0; c < chains.size(); ++c) {
      if (crease[c] || !consistent[c]) continue;
      for (int i : chains[c])
        if (end[std::size_t(T.E[std::size_t(i)].a)] || end[std::size_t(T.E[std::size_t(i)].b)]) {
          grown[c] = 1;
          grew = true;
          break;
        }
    }
    for (std::size_t c = 0; c < chains.size(); ++c) crease[c] = crease[c] || grown[c];
  }
}

}  // namespace

std::size_t Creases::creaseNodes() const { return std::size_t(std::count(node.begin(), node.end(), char(1))); }
std::size_t Creases::cornerNodes() const { return std::size_t(std::count(corner.begin(), corner.end(), char(1))); }

std::string Creases::summary() const {
  const std::size_t rejectedEdges = sharpEdges - creaseEdges;
  char noise[32];
  std::snprintf(noise, sizeof noise, "; median dihedral %.1f deg", noiseDeg);
  if (chains.empty())
    return "no crease: " + std::to_string(sharpEdges) + " sharp edges, " +
           (sharpEdges ? "all taken for noise" : std::string("none")) + " (no node fixed as a feature)" + noise;
  return std::to_string(chains.size()) + " crease chains (" + std::to_string(creaseEdges) + " edges, " +
         std::to_string(creaseNodes()) + " nodes, " + std::to_string(cornerNodes()) + " corners); " +
         std::to_string(rejectedEdges) + " of " + std::to_string(sharpEdges) + " sharp edges taken for noise" + noise;
}

Creases detectCreases(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& F,
                      const std::vector<std::uint64_t>& ignored, const CreaseOptions& opt) {
  return detectCreases(V, F, Topology(Surface{V, F}), ignored, opt);
}

Creases detectCreases(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& F, const Topology& topo,
                      const std::vector<std::uint64_t>& ignored, const CreaseOptions& opt) {
  const std::size_t nv = V.size();
  const EdgeTable T(V, F, topo);
  Creases out;

  // 1. sharp edges, and the mesh's noise level
  const std::vector<char> sharp = sharpEdges(T, ignored, opt);
  out.sharpEdges = std::size_t(std::count(sharp.begin(), sharp.end(), char(1)));
  out.noiseDeg = noiseLevel(T, ignored, sharp);

  // 2. chains of linked sharp edges
  std::vector<std::vector<int>> nodeSharp(nv);
  for (std::size_t i = 0; i < T.E.size(); ++i)
    if (sharp[i]) nodeSharp[std::size_t(T.E[i].a)].push_back(int(i)), nodeSharp[std::size_t(T.E[i].b)].push_back(int(i));
  const auto chains = linkChains(V, T, sharp, nodeSharp, opt);

  // 3. creases: consistent and structural chains, and the consistent ones that continue them
  const std::vector<char> consistent = consistentChains(T, chains, smoothWings(T, sharp), out.noiseDeg, opt);
  const std::vector<char> structural = structuralChains(T, chains, consistent, nodeSharp, opt);
  std::vector<char> crease(chains.size(), 0);
  for (std::size_t c = 0; c < chains.size(); ++c) crease[c] = consistent[c] && structural[c];
  growAlongCreases(T, chains, consistent, nv, crease);

  // the crease chains, their nodes and corners
  out.node.assign(nv, 0);
  out.corner.assign(nv, 0);
  std::vector<int> creaseDegree(nv, 0);
  for (std::size_t c = 0; c < chains.size(); ++c) {
    if (!crease[c]) {
      ++out.rejectedChains;
      continue;
    }
    std::vector<std::array<int, 2>> edges;
    for (int i : chains[c]) {
      const Edge& e = T.E[std::size_t(i)];
      edges.push_back({e.a, e.b});
      out.node[std::size_t(e.a)] = out.node[std::size_t(e.b)] = 1;
      ++creaseDegree[std::size_t(e.a)], ++creaseDegree[std::size_t(e.b)];
    }
    out.creaseEdges += edges.size();
    out.chains.push_back(std::move(edges));
  }
  for (std::size_t v = 0; v < nv; ++v) out.corner[v] = creaseDegree[v] == 1 || creaseDegree[v] >= 3;
  return out;
}

}  // namespace pectus::smooth
