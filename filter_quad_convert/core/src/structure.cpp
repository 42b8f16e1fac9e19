#include "pectus/quad/structure.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <unordered_map>

namespace pectus::quad {

namespace {

std::uint64_t edgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

Poly tri(int a, int b, int c) {
  Poly p;
  p.nv = 3;
  p.v = {a, b, c, -1};
  return p;
}
Poly quadOf(int a, int b, int c, int d) {
  Poly p;
  p.nv = 4;
  p.v = {a, b, c, d};
  return p;
}
/// rotate so that vertex v is at position 0 (v must be in p)
Poly rotateTo(const Poly& p, int v) {
  Poly r = p;
  int k = 0;
  while (p.v[k] != v) ++k;
  for (int j = 0; j < p.nv; ++j) r.v[j] = p.v[(k + j) % p.nv];
  return r;
}

class Work {
 public:
  Work(PolyMesh& m, const c1::C1Surface* surf, const StructureOptions& o, bool quadMode)
      : m_(m), surf_(surf), o_(o), quadMode_(quadMode) {
    cosFlatHalf_ = std::cos(0.5 * o.maxDihedralDeg * M_PI / 180.0);
    cosFlat_ = std::cos(o.maxDihedralDeg * M_PI / 180.0);
    rebuild();
    double sum = 0;
    for (const auto& kv : edgeElems_) sum += (m_.V[kv.first >> 32] - m_.V[kv.first & 0xffffffffu]).norm();
    meanEdge_ = edgeElems_.empty() ? 0 : sum / double(edgeElems_.size());
  }

  std::size_t swaps = 0, eliminations = 0, divisions = 0;

  /// compacts, rebuilds adjacency, valences, boundary; clears the per-step locks
  void rebuild() {
    std::vector<Poly> F;
    F.reserve(m_.F.size());
    for (std::size_t i = 0; i < m_.F.size(); ++i)
      if (i >= dead_.size() || !dead_[i]) F.push_back(m_.F[i]);
    m_.F.swap(F);
    dead_.assign(m_.F.size(), 0);
    dirty_.assign(m_.F.size(), 0);
    valences(m_, val_, bnd_);
    vertElems_.assign(m_.V.size(), {});
    edgeElems_.clear();
    edgeUse_.clear();
    for (int f = 0; f < int(m_.F.size()); ++f) {
      const auto& p = m_.F[f];
      for (int k = 0; k < p.nv; ++k) {
        vertElems_[p.v[k]].push_back(f);
        const auto e = edgeKey(p.v[k], p.v[(k + 1) % p.nv]);
        edgeElems_[e].push_back(f);
        ++edgeUse_[e];
      }
    }
  }

  bool eligible(int f) const { return !dead_[f] && !dirty_[f] && (quadMode_ ? m_.F[f].nv == 4 : m_.F[f].nv == 3); }

  Vec3 normalOf(const Poly& p) const {
    const auto& X = m_.V;
    if (p.nv == 3) return (X[p.v[1]] - X[p.v[0]]).cross(X[p.v[2]] - X[p.v[0]]);
    return 0.5 * (X[p.v[2]] - X[p.v[0]]).cross(X[p.v[3]] - X[p.v[1]]);
  }

  /// reference normal of old elements; false if they are not nearly coplanar (operators keep the surface)
  bool flat(const std::vector<int>& elems, Vec3& n) const {
    n = Vec3::Zero();
    std::vector<Vec3> ns;
    for (int f : elems) {
      Vec3 e = normalOf(m_.F[f]);
      if (e.norm() <= 0) return false;
      n += e;
      ns.push_back(e.normalized());
    }
    if (n.norm() <= 0) return false;
    n.normalize();
    for (const auto& e : ns)
      if (e.dot(n) < cosFlatHalf_) return false;
    return true;
  }

  double minQuality(const std::vector<int>& elems) const {
    double q = 1e300;
    for (int f : elems) q = std::min(q, polyQuality(m_, m_.F[f]));
    return q;
  }

  /// minimum quality of new elements, or -1 if one is invalid along n, folded, or makes an edge non-manifold
  double newQuality(const std::vector<Poly>& polys, const Vec3& n, const std::vector<int>& old) const {
    const auto& X = m_.V;
    double q = 1e300;
    std::map<std::uint64_t, int> use;
    for (int f : old) {
      const auto& p = m_.F[f];
      for (int k = 0; k < p.nv; ++k) --use[edgeKey(p.v[k], p.v[(k + 1) % p.nv])];
    }
    for (const auto& p : polys) {
      for (int k = 0; k < p.nv; ++k) ++use[edgeKey(p.v[k], p.v[(k + 1) % p.nv])];
      double e;
      if (p.nv == 3) {
        e = triangleAlphaSigned(X[p.v[0]], X[p.v[1]], X[p.v[2]], n);
      } else {
        e = std::min(quadBeta(X[p.v[0]], X[p.v[1]], X[p.v[2]], X[p.v[3]]),
                     quadBetaWithNormal(X[p.v[0]], X[p.v[1]], X[p.v[2]], X[p.v[3]], n));
      }
      if (!(e > 0)) return -1;
      const Vec3 pn = normalOf(p);
      if (pn.norm() <= 0 || pn.normalized().dot(n) < cosFlat_) return -1;
      q = std::min(q, polyQuality(m_, p));
    }
    for (const auto& kv : use) {
      const auto it = edgeUse_.find(kv.first);
      const int now = it == edgeUse_.end() ? 0 : it->second;
      if (now + kv.second > 2) return -1;
    }
    return q;
  }

  /// change of sum over interior nodes of (valence - ideal)^2 if `old` is replaced by `polys`
  double energyDelta(const std::vector<int>& old, const std::vector<Poly>& polys) const {
    std::map<int, int> d;
    for (int f : old)
      for (int k = 0; k < m_.F[f].nv; ++k) --d[m_.F[f].v[k]];
    for (const auto& p : polys)
      for (int k = 0; k < p.nv; ++k) ++d[p.v[k]];
    const int ideal = quadMode_ ? 4 : 6;
    double de = 0;
    for (const auto& [v, dv] : d) {
      if (dv == 0) continue;
      if (v < int(bnd_.size()) && bnd_[v]) continue;
      const int before = v < int(val_.size()) ? val_[v] : 0;
      const int after = before + dv;
      const double eb = before > 0 ? double((before - ideal) * (before - ideal)) : 0.0;
      const double ea = after > 0 ? double((after - ideal) * (after - ideal)) : 0.0;
      de += ea - eb;
    }
    return de;
  }

  void replace(const std::vector<int>& old, const std::vector<Poly>& polys) {
    for (int f : old) {
      dead_[f] = 1;
      const auto& p = m_.F[f];
      for (int k = 0; k < p.nv; ++k) {
        --val_[p.v[k]];
        --edgeUse_[edgeKey(p.v[k], p.v[(k + 1) % p.nv])];
      }
    }
    for (Poly p : polys) {
      chooseDiagonal(m_, p);  // new quads: the better of the two triangulations in MeshLab
      m_.F.push_back(p);
      dead_.push_back(0);
      dirty_.push_back(1);
      for (int k = 0; k < p.nv; ++k) {
        if (p.v[k] >= int(val_.size())) {
          val_.resize(p.v[k] + 1, 0);
          bnd_.resize(p.v[k] + 1, 0);
        }
        ++val_[p.v[k]];
        ++edgeUse_[edgeKey(p.v[k], p.v[(k + 1) % p.nv])];
      }
    }
  }

  /// the two eligible elements of an interior edge, each rotated so the edge is its first side: p = (a, b, ..),
  /// q = (b, a, ..). False if the edge is not interior or an element is locked.
  bool edgePair(std::uint64_t e, int& f0, int& f1, Poly& p, Poly& q) const {
    const auto it = edgeElems_.find(e);
    if (it == edgeElems_.end() || it->second.size() != 2) return false;
    f0 = it->second[0];
    f1 = it->second[1];
    if (!eligible(f0) || !eligible(f1)) return false;
    const int a = int(e >> 32), b = int(e & 0xffffffffu);
    // orient: p has a -> b
    for (int t = 0; t < 2; ++t) {
      const Poly& P = m_.F[t ? f1 : f0];
      for (int k = 0; k < P.nv; ++k)
        if (P.v[k] == a && P.v[(k + 1) % P.nv] == b) {
          p = rotateTo(P, a);
          q = rotateTo(m_.F[t ? f0 : f1], b);
          if (q.v[1] != a) return false;  // inconsistent orientation
          if (t) std::swap(f0, f1);
          return true;
        }
    }
    for (int t = 0; t < 2; ++t) {
      const Poly& P = m_.F[t ? f1 : f0];
      for (int k = 0; k < P.nv; ++k)
        if (P.v[k] == b && P.v[(k + 1) % P.nv] == a) {
          p = rotateTo(P, b);
          q = rotateTo(m_.F[t ? f0 : f1], a);
          if (q.v[1] != b) return false;
          if (t) std::swap(f0, f1);
          return true;
        }
    }
    return false;
  }

  std::vector<std::uint64_t> sortedEdges() const {
    std::vector<std::uint64_t> es;
    es.reserve(edgeElems_.size());
    for (const auto& kv : edgeElems_) es.push_back(kv.first);
    std::sort(es.begin(), es.end());
    return es;
  }

  /// best of several candidate element sets: (quality, index), quality -1 if none valid
  std::pair<double, int> best(const std::vector<std::vector<Poly>>& options, const Vec3& n, const std::vector<int>& old) const {
    std::pair<double, int> b{-1, -1};
    for (int i = 0; i < int(options.size()); ++i) {
      const double q = newQuality(options[i], n, old);
      if (q > b.first) b = {q, i};
    }
    return b;
  }

  bool tryApply(const std::vector<int>& old, const std::vector<std::vector<Poly>>& options, bool needEnergy, std::size_t& counter) {
    Vec3 n;
    if (!flat(old, n)) return false;
    const double before = minQuality(old);
    // candidates ordered by quality; take the best acceptable one
    std::vector<std::pair<double, int>> ranked;
    for (int i = 0; i < int(options.size()); ++i) ranked.push_back({newQuality(options[i], n, old), i});
    std::sort(ranked.rbegin(), ranked.rend());
    for (const auto& [q, i] : ranked) {
      if (q <= 0 || q < before - 1e-12) break;
      const double de = energyDelta(old, options[i]);
      const bool ok = needEnergy ? (de < 0 || (de == 0 && q > before + 1e-4)) : q > before + 1e-6;
      if (!ok) continue;
      replace(old, options[i]);
      ++counter;
      return true;
    }
    return false;
  }

  // ---------------------------------------------------------------------------------------------------------

  std::size_t swapPass() {
    std::size_t done = 0;
    for (auto e : sortedEdges()) {
      int f0, f1;
      Poly p, q;
      if (!edgePair(e, f0, f1, p, q)) continue;
      std::vector<std::vector<Poly>> opt;
      if (!quadMode_) {
        // p = (a, b, c), q = (b, a, d) -> (a, d, c), (b, c, d)
        const int a = p.v[0], b = p.v[1], c = p.v[2], d = q.v[2];
        if (c == d) continue;
        opt.push_back({tri(a, d, c), tri(b, c, d)});
      } else {
        // hexagon H = b, p2, p3, a, q2, q3 (p = a b p2 p3, q = b a q2 q3); alternative diagonals H1-H4, H2-H5
        const int H[6] = {p.v[1], p.v[2], p.v[3], p.v[0], q.v[2], q.v[3]};
        opt.push_back({quadOf(H[1], H[2], H[3], H[4]), quadOf(H[4], H[5], H[0], H[1])});
        opt.push_back({quadOf(H[2], H[3], H[4], H[5]), quadOf(H[5], H[0], H[1], H[2])});
      }
      done += tryApply({f0, f1}, opt, true, swaps);
    }
    return done;
  }

  std::size_t eliminatePass() {
    std::size_t done = 0;
    const int nv = int(vertElems_.size());
    for (int v = 0; v < nv; ++v) {
      if (bnd_[v]) continue;
      const auto& es = vertElems_[v];
      const int k = int(es.size());
      if (quadMode_ ? (k != 2 && k != 3) : k != 3) continue;
      bool ok = true;
      for (int f : es) ok = ok && eligible(f);
      if (!ok) continue;
      // ring in order: element i = (v, next_i, ..., prev_i); next_{i+1} = prev_i
      std::vector<Poly> rs;
      for (int f : es) rs.push_back(rotateTo(m_.F[f], v));
      std::vector<int> order{0};
      std::vector<char> used(k, 0);
      used[0] = 1;
      for (int s = 1; s < k && ok; ++s) {
        const Poly& cur = rs[order.back()];
        const int prev = cur.v[cur.nv - 1];
        int nx = -1;
        for (int j = 0; j < k; ++j)
          if (!used[j] && rs[j].v[1] == prev) nx = j;
        if (nx < 0) ok = false;
        else {
          used[nx] = 1;
          order.push_back(nx);
        }
      }
      if (!ok || rs[order.back()].v[rs[order.back()].nv - 1] != rs[order[0]].v[1]) continue;
      std::vector<int> ring;  // boundary of the union, counter-clockwise
      for (int i : order)
        for (int j = 1; j < rs[i].nv - 1; ++j) ring.push_back(rs[i].v[j]);
      std::vector<int> sorted = ring;
      std::sort(sorted.begin(), sorted.end());
      if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;
      std::vector<std::vector<Poly>> opt;
      const auto& R = ring;
      if (!quadMode_ && k == 3) opt.push_back({tri(R[0], R[1], R[2])});
      if (quadMode_ && k == 2) opt.push_back({quadOf(R[0], R[1], R[2], R[3])});
      if (quadMode_ && k == 3)
        for (int s = 0; s < 3; ++s)
          opt.push_back({quadOf(R[s], R[s + 1], R[s + 2], R[s + 3]), quadOf(R[s + 3], R[(s + 4) % 6], R[(s + 5) % 6], R[s])});
      std::vector<int> old(es.begin(), es.end());
      done += tryApply(old, opt, true, eliminations);
    }
    return done;
  }

  std::size_t dividePass() {
    std::size_t done = 0;
    const double limit = o_.longEdgeFactor * meanEdge_;
    for (auto e : sortedEdges()) {
      const int a = int(e >> 32), b = int(e & 0xffffffffu);
      if ((m_.V[a] - m_.V[b]).norm() <= limit) continue;
      int f0, f1;
      Poly p, q;
      if (!edgePair(e, f0, f1, p, q)) continue;
      const Vec3 mid = 0.5 * (m_.V[a] + m_.V[b]);
      const Vec3 pos = surf_ ? surf_->closestPoint(mid).point : mid;
      const int mi = int(m_.V.size());
      m_.V.push_back(pos);
      std::vector<std::vector<Poly>> opt;
      if (!quadMode_) {
        const int pa = p.v[0], pb = p.v[1], c = p.v[2], d = q.v[2];
        opt.push_back({tri(pa, mi, c), tri(mi, pb, c), tri(pb, mi, d), tri(mi, pa, d)});
      } else {
        const int H[6] = {p.v[1], p.v[2], p.v[3], p.v[0], q.v[2], q.v[3]};
        for (int s = 0; s < 2; ++s)
          opt.push_back({quadOf(mi, H[s], H[s + 1], H[s + 2]), quadOf(mi, H[s + 2], H[s + 3], H[(s + 4) % 6]),
                         quadOf(mi, H[(s + 4) % 6], H[(s + 5) % 6], H[s])});
      }
      if (tryApply({f0, f1}, opt, false, divisions)) ++done;
      else m_.V.pop_back();
    }
    return done;
  }

  /// removes the nodes no element uses any more (eliminated nodes); the others keep their order
  void dropUnreferenced() {
    std::vector<int> map(m_.V.size(), -1);
    for (const auto& p : m_.F)
      for (int k = 0; k < p.nv; ++k) map[p.v[k]] = 0;
    std::vector<Vec3> V;
    for (std::size_t i = 0; i < m_.V.size(); ++i)
      if (map[i] == 0) {
        map[i] = int(V.size());
        V.push_back(m_.V[i]);
      }
    for (auto& p : m_.F)
      for (int k = 0; k < p.nv; ++k) p.v[k] = map[p.v[k]];
    m_.V.swap(V);
  }

 private:
  PolyMesh& m_;
  const c1::C1Surface* surf_;
  const StructureOptions& o_;
  bool quadMode_;
  double cosFlatHalf_ = 0, cosFlat_ = 0, meanEdge_ = 0;
  std::vector<char> dead_, dirty_, bnd_;
  std::vector<int> val_;
  std::vector<std::vector<int>> vertElems_;
  std::unordered_map<std::uint64_t, std::vector<int>> edgeElems_;
  std::unordered_map<std::uint64_t, int> edgeUse_;
};

}  // namespace

StructureResult improveStructure(const PolyMesh& in, const c1::C1Surface* surface, const StructureOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  requirePolyMesh(in);  // (unchecked, a NaN vertex would go through and a bad index be read out of range)
  StructureResult r;
  r.before = polyStats(in);
  r.mesh = in;
  const bool quadMode = in.quads() > 0;
  Work w(r.mesh, surface, o, quadMode);
  for (int pass = 0; pass < o.maxPasses; ++pass) {
    std::size_t changed = 0;
    if (o.swap) {
      changed += w.swapPass();
      w.rebuild();
    }
    if (o.eliminate) {
      changed += w.eliminatePass();
      w.rebuild();
    }
    if (o.divide) {
      changed += w.dividePass();
      w.rebuild();
    }
    r.passes = pass + 1;
    if (!changed) break;
  }
  w.dropUnreferenced();
  r.swaps = w.swaps;
  r.eliminations = w.eliminations;
  r.divisions = w.divisions;
  r.after = polyStats(r.mesh);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace pectus::quad
