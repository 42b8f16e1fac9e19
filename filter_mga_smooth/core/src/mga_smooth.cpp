#include "pectus/smooth/mga_smooth.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <set>
#include <utility>

#include "pectus/smooth/creases.h"
#include "pectus/c1/surface.h"
#include "pectus/surface_cmesh.h"
#include "pectus/c1/surface.h"
#include "pectus/element_quality.h"
#include "pectus/errors.h"
#include "pectus/folds.h"
#include "pectus/mesh_checks.h"
#include "pectus/self_intersections.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pectus::smooth {

using c1::C1Surface;

namespace {

/// Location of a node on the original surface: patch and (s, t), bary = (1-s-t, s, t).
struct Loc {
  int face = -1;
  double s = 0, t = 0;
};

/// unit normal of the C1 surface at a location (+z for a node not located on the surface)
Vec3 normalAt(const C1Surface& S, const Loc& l) {
  return l.face >= 0 ? S.at(l.face, Vec3(1 - l.s - l.t, l.s, l.t)).normal : Vec3(0, 0, 1);
}

/// Local projection onto the C1 surface. A walk over the flat triangles of the original mesh first finds
/// the triangle whose plane projection of q has non-negative barycentric coordinates (no patch
/// evaluation), then Gauss-Newton on that patch from those coordinates, walking across edges if the
/// iterate leaves the patch; the global closestPoint if the walk fails.
/// Gauss-Newton stops when the step in (s, t) is below this (a 1e-8 fraction of the patch: far below the
/// micro-GA accuracy)
constexpr double kProjTol = 1e-8;
/// In the micro-GA's search, the last Gauss-Newton step is taken to first order once it is below this
/// (see Projector::project): a candidate is then off the patch by O(step^2), ~1e-6 of the patch size,
/// far below the search's resolution (accuracy 1e-3 of an edge), and most candidates cost one patch
/// evaluation instead of two or three. The move itself is the exact surface point at the best location.
constexpr double kSearchLinTol = 1e-3;
class Projector {
 public:
  Projector(const C1Surface& S) : S_(S), adj_(S.faceNeighbours()) {
    const auto& F = S.mesh().F;
    const auto& V = S.mesh().V;
    flat_.resize(F.size());
    for (std::size_t f = 0; f < F.size(); ++f) {
      Flat& fl = flat_[f];
      fl.a = V[std::size_t(F[f][0])];
      fl.e1 = V[std::size_t(F[f][1])] - fl.a;
      fl.e2 = V[std::size_t(F[f][2])] - fl.a;
      const double m11 = fl.e1.dot(fl.e1), m12 = fl.e1.dot(fl.e2), m22 = fl.e2.dot(fl.e2);
      const double det = m11 * m22 - m12 * m12;
      fl.ok = det > 1e-14 * m11 * m22 && det > 0;
      if (fl.ok) {
        // (s, t) = rows of M^-1 [e1 e2]^T applied to (q - a)
        fl.gs = (m22 * fl.e1 - m12 * fl.e2) / det;
        fl.gt = (m11 * fl.e2 - m12 * fl.e1) / det;
      }
    }
  }

  /// Projects q starting at `start`; returns the location, point and unit normal.
  Loc project(const Vec3& q, Loc start, Vec3& P, Vec3& N, double linTol = kProjTol) const {
    const auto& F = S_.mesh().F;
    int f = start.face, prev = -1;
    double s = start.s, t = start.t;
    flatWalk(q, f, s, t);
    for (int walk = 0; walk < 24; ++walk) {
      for (int it = 0; it < 10; ++it) {
        const c1::PatchJet j = S_.jet(f, Vec3(1 - s - t, s, t));
        const Vec3 r = j.P - q;
        const double h11 = j.Ps.dot(j.Ps), h12 = j.Ps.dot(j.Pt), h22 = j.Pt.dot(j.Pt);
        const double det = h11 * h22 - h12 * h12;
        if (!(det > 1e-30)) break;
        const double gs = j.Ps.dot(r), gt = j.Pt.dot(r);
        const double ds = -(h22 * gs - h12 * gt) / det, dt = -(h11 * gt - h12 * gs) / det;
        if (!std::isfinite(ds) || !std::isfinite(dt)) break;
        const double step = std::abs(ds) + std::abs(dt);
        if (step < linTol) {
          // converged: below kProjTol, j is the point at (s, t); below linTol, the last Gauss-Newton
          // step is taken to first order (P + Ps ds + Pt dt, off the patch by O(step^2)) instead of
          // evaluating the patch again. Inside the patch it is the answer.
          const bool lin = step >= kProjTol;
          const double s1 = lin ? s + ds : s, t1 = lin ? t + dt : t;
          if (s1 >= 0 && t1 >= 0 && s1 + t1 <= 1) {
            const Vec3 nrm = j.normal();
            if (nrm.squaredNorm() > 0) {
              P = lin ? Vec3(j.P + ds * j.Ps + dt * j.Pt) : j.P;
              N = nrm;
              return Loc{f, s1, t1};
            }
          }
          if (!lin) break;
        }
        s += ds;
        t += dt;
        if (s < -0.5 || t < -0.5 || s + t > 1.5) break;  // far outside this patch: walk
      }
      Vec3 b(1 - s - t, s, t);
      int l = 0;
      b.minCoeff(&l);
      if (b[l] >= -1e-9 || !b.allFinite()) {
        if (!b.allFinite()) b = Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
        b = b.cwiseMax(0.0);
        b /= b.sum();
        return finish(f, b, P, N);
      }
      const int nb = adj_[std::size_t(f)][std::size_t(l)];
      b[l] = 0;
      b = b.cwiseMax(0.0);
      if (b.sum() <= 0) b = Vec3(0, 0.5, 0.5), b[l] = 0, b /= b.sum();
      b /= b.sum();
      if (nb < 0 || nb == prev) return finish(f, b, P, N);  // boundary, or bouncing on the edge
      // transfer the edge point to the neighbour patch (C0 across edges: the same point)
      Vec3 nbBary(0, 0, 0);
      for (int k = 0; k < 3; ++k) {
        if (k == l) continue;
        const int v = F[std::size_t(f)][std::size_t(k)];
        for (int m = 0; m < 3; ++m)
          if (F[std::size_t(nb)][std::size_t(m)] == v) nbBary[m] = b[k];
      }
      prev = f;
      f = nb;
      s = nbBary[1];
      t = nbBary[2];
    }
    const c1::SurfacePoint sp = S_.closestPoint(q);
    return finish(sp.face, sp.bary, P, N);
  }

  Loc finish(int f, const Vec3& b, Vec3& P, Vec3& N) const {
    const c1::SurfacePoint sp = S_.at(f, b);
    P = sp.point;
    N = sp.normal;
    Loc L;
    L.face = f;
    L.s = sp.bary[1];
    L.t = sp.bary[2];
    return L;
  }

 private:
  struct Flat {
    Vec3 a, e1, e2, gs, gt;
    bool ok = false;
  };
  /// moves (f, s, t) to the flat triangle whose plane projection of q lies inside it (or the last one
  /// reached: a boundary, a degenerate triangle, a cycle), with those coordinates clamped to it
  void flatWalk(const Vec3& q, int& f, double& s, double& t) const {
    int prev = -1;
    for (int step = 0; step < 64; ++step) {
      const Flat& fl = flat_[std::size_t(f)];
      if (!fl.ok) return;
      const Vec3 d = q - fl.a;
      const double fs = fl.gs.dot(d), ft = fl.gt.dot(d);
      const Vec3 b(1 - fs - ft, fs, ft);
      int l = 0;
      b.minCoeff(&l);
      const int nb = b[l] < -1e-12 ? adj_[std::size_t(f)][std::size_t(l)] : -1;
      if (nb < 0 || nb == prev) {
        Vec3 c = b.cwiseMax(0.0);
        c /= c.sum();
        s = c[1];
        t = c[2];
        return;
      }
      prev = f;
      f = nb;
    }
  }

  const C1Surface& S_;
  std::vector<std::array<int, 3>> adj_;
  std::vector<Flat> flat_;
};

struct Mesh {
  std::vector<Vec3> X;                  // current positions (compact indices)
  std::vector<Element> E;               // compact vertex indices
  std::vector<std::vector<int>> vE;     // node -> elements
  std::vector<Vec3> N;                  // unit normal of the C1 surface at each node's current position
};

/// the normal to test node k of element e against: `nrm` for node n (the candidate's), M.N for the others
inline const Vec3& nodeNormal(const Mesh& M, const Element& e, int k, int n, const Vec3& nrm) {
  return e.v[k] == n ? nrm : M.N[std::size_t(e.v[k])];
}

/// quality of the element at positions p (alpha, or beta for a quad) and whether it is unfolded: valid in
/// itself and its signed area (a quad: every Knupp corner area) positive along the surface normal at each
/// of its nodes, so that no node's move can fold an element against another node's normal. The element's
/// shape (TriangleShape / QuadCorners) is computed once for its quality and all its fold tests.
inline double elementQuality(const Mesh& M, const Element& e, const Vec3* p, int n, const Vec3& nrm, bool& ok) {
  ok = false;
  if (e.nv == 3) {
    const TriangleShape t(p[0], p[1], p[2]);
    const double q = t.alpha();
    if (!(q > 1e-12)) return q;
    // alphaSigned(normal) > 1e-12, without its division (edgeSum > 0 since q > 0)
    const double lim = 1e-12 / (2.0 * std::sqrt(3.0)) * t.edgeSum;
    for (int k = 0; k < 3; ++k)
      if (!(t.cross.dot(nodeNormal(M, e, k, n, nrm)) > lim)) return q;
    ok = true;
    return q;
  }
  const QuadCorners c(p[0], p[1], p[2], p[3]);
  const double q = c.beta();
  if (!(q > 1e-12)) return q;
  for (int k = 0; k < 4; ++k)
    if (!(c.betaWithNormal(nodeNormal(M, e, k, n, nrm)) > 1e-12)) return q;
  ok = true;
  return q;
}

/// fitness of node n at position x with surface normal nrm: sum of element qualities (cap > 0, the final
/// pass: the worst element's quality up to the cap, plus kCapSumWeight times the sum) if none is folded
/// (elementQuality() above) and the worst is not below the guard, else below any valid value. A worst
/// element below the guard ranks below everything else, invalid stars included: the node's start respects
/// its guard, so the guard holds whatever the star (else a star starting with two elements folded against
/// the surface normal can trade one of them for an element of alpha 1.5e-5, below the guard:
/// tests/fuzz/corpus/mga/guard-folded-bipyramid).
/// Invalid stars rank lexicographically: first by the elements invalid in themselves (a reflex, folded or
/// degenerate quad along its own normal, a degenerate triangle), then by those folded only against the
/// surface normal at a node, then by the sum; so a star that starts with an element folded against the
/// node's normal (a nearly flat corner on a curved surface) can never trade it for an element invalid in
/// itself.
constexpr double kCapSumWeight = 0.01;
/// the fitness of a star from its elements' sum and worst quality and the counts of broken (quality not
/// positive) and invalid (folded) elements, as described above
inline double rankStar(double sum, double lo, int broken, int invalid, double guard, double cap) {
  if (lo < guard) return -1e9 + 0.01 * sum;
  if (broken || invalid) return -1e4 * broken - 100.0 * invalid + 0.01 * sum;
  return cap > 0 ? std::min(lo, cap) + kCapSumWeight * sum : sum;
}
double fitnessAt(const Mesh& M, int n, const Vec3& x, const Vec3& nrm, double guard, double cap = 0,
                 double* minQ = nullptr) {
  double sum = 0, lo = 1e300;
  int invalid = 0, broken = 0;
  Vec3 p[4];
  for (int ei : M.vE[std::size_t(n)]) {
    const Element& e = M.E[std::size_t(ei)];
    for (int k = 0; k < e.nv; ++k) p[k] = e.v[k] == n ? x : M.X[std::size_t(e.v[k])];
    bool ok;
    const double q = elementQuality(M, e, p, n, nrm, ok);
    if (!(q > 1e-12)) ++broken;
    else if (!ok) ++invalid;
    sum += q;
    lo = std::min(lo, q);
  }
  if (minQ) *minQ = lo;
  return rankStar(sum, lo, broken, invalid, guard, cap);
}

QualityStats stats(const Mesh& M) { return summarizeQuality(elementQualities(M.E, M.X), 10); }

/// elements folded against the surface normal at one of their nodes, or invalid in themselves
std::size_t foldedElements(const Mesh& M) {
  std::size_t folded = 0;
  Vec3 p[4];
  for (const auto& e : M.E) {
    for (int k = 0; k < e.nv; ++k) p[k] = M.X[std::size_t(e.v[k])];
    bool ok;
    elementQuality(M, e, p, -1, p[0], ok);
    folded += !ok;
  }
  return folded;
}

/// A node's star of triangles gathered once per search (positions and normals of the other two nodes of
/// each triangle, in the triangle's orientation), so that a candidate's fitness reads no mesh arrays:
/// the same value as fitnessAt() (up to rounding: each triangle is taken from the node's corner).
class TriStar {
 public:
  /// false if the node has an element that is not a triangle, or more than kMax
  bool gather(const Mesh& M, int n) {
    nt_ = 0;
    const auto& vE = M.vE[std::size_t(n)];
    if (vE.size() > kMax) return false;
    for (int ei : vE) {
      const Element& e = M.E[std::size_t(ei)];
      if (e.nv != 3) return false;
      int k = 0;
      while (e.v[k] != n) ++k;
      Tri& t = t_[nt_++];
      const int b = e.v[(k + 1) % 3], c = e.v[(k + 2) % 3];
      t.b = M.X[std::size_t(b)];
      t.c = M.X[std::size_t(c)];
      t.nb = M.N[std::size_t(b)];
      t.nc = M.N[std::size_t(c)];
      t.bc2 = (t.c - t.b).squaredNorm();
    }
    return true;
  }
  /// fitnessAt() for this star (minQ: the worst element's quality)
  double fitness(const Vec3& x, const Vec3& nrm, double guard, double cap, double* minQ = nullptr) const {
    constexpr double kAlpha = 2.0 * 1.7320508075688772;  // 2 sqrt(3): alpha = kAlpha |cross| / edge sum
    double sum = 0, lo = 1e300;
    int invalid = 0, broken = 0;
    for (int i = 0; i < nt_; ++i) {
      const Tri& t = t_[i];
      const Vec3 db = t.b - x, dc = t.c - x;
      const Vec3 cr = db.cross(dc);
      const double es = db.squaredNorm() + dc.squaredNorm() + t.bc2;
      const double q = es > 0.0 ? kAlpha * cr.norm() / es : 0.0;
      if (!(q > 1e-12)) {
        ++broken;
      } else {
        // alphaSigned(normal) > 1e-12 at each of the three nodes
        const double lim = 1e-12 / kAlpha * es;
        if (!(cr.dot(nrm) > lim) || !(cr.dot(t.nb) > lim) || !(cr.dot(t.nc) > lim)) ++invalid;
      }
      sum += q;
      lo = std::min(lo, q);
    }
    if (minQ) *minQ = lo;
    return rankStar(sum, lo, broken, invalid, guard, cap);
  }

 private:
  static constexpr std::size_t kMax = 32;
  struct Tri {
    Vec3 b, c, nb, nc;
    double bc2;
  };
  std::array<Tri, kMax> t_;
  int nt_ = 0;
};

/// One node's search: where it starts, the guard, and the best candidate found so far.
struct NodeSearch {
  const Mesh& M;
  const Projector& proj;
  int n;
  Vec3 x0, n0;       ///< position and surface normal now
  Loc l0;
  double guard;      ///< the node's worst element may not drop below this
  double cap;        ///< > 0: final pass fitness (the worst element up to cap, then the sum)
  double startFit;   ///< fitness at x0 (< 0: the star is folded or invalid, or below the guard)
  double bestFit;
  Vec3 bestX;
  Loc bestLoc;
  double bestDist = 0;  ///< candidate-to-surface distance of the best
  std::size_t evaluations = 0;
  const TriStar* star = nullptr;  ///< the node's triangles, if gathered (else the mesh arrays are read)
  double linTol = kProjTol;       ///< Projector::project's first-order tolerance for the candidates

  /// fitness at surface point P with unit normal N
  double fitness(const Vec3& P, const Vec3& N) const {
    return star ? star->fitness(P, N, guard, cap) : fitnessAt(M, n, P, N, guard, cap);
  }
  /// fitness of the surface point nearest to q (projected from the node's location); P, L: that point
  double eval(const Vec3& q, Vec3& P, Loc& L) {
    Vec3 N;
    L = proj.project(q, l0, P, N, linTol);
    ++evaluations;
    return fitness(P, N);
  }
  void offer(double fit, const Vec3& P, const Loc& L, const Vec3& q) {
    if (fit > bestFit) {
      bestFit = fit;
      bestX = P;
      bestLoc = L;
      bestDist = (P - q).norm();
    }
  }
};

/// a node's fan: the triangles of its elements as (V2, V3), V1 = node, in boundary order (a quad gives two)
using Fan = std::vector<std::pair<int, int>>;

/// the fan of node n (the buffer is reused)
void gatherFan(const Mesh& M, int n, Fan& fan) {
  fan.clear();
  for (int ei : M.vE[std::size_t(n)]) {
    const Element& e = M.E[std::size_t(ei)];
    int k = 0;
    while (e.v[k] != n) ++k;
    if (e.nv == 3) {
      fan.push_back({e.v[(k + 1) % 3], e.v[(k + 2) % 3]});
    } else {
      fan.push_back({e.v[(k + 1) % 4], e.v[(k + 2) % 4]});
      fan.push_back({e.v[(k + 2) % 4], e.v[(k + 3) % 4]});
    }
  }
}

/// The micro-GA in one triangle of a node's fan (thesis steps 3-7); its best is offered to the node's search.
class FanSearch {
 public:
  /// onPlane: the candidates are measured on the triangle's plane with the node's normal (no projection),
  /// only the triangle's best is projected and measured on the surface
  FanSearch(NodeSearch& ns, const Fan& fan, const mga::Options& mo, std::uint64_t nodeSeed, bool onPlane)
      : ns_(ns), fan_(fan), mo_(mo), nodeSeed_(nodeSeed), onPlane_(onPlane) {}

  /// the micro-GA in fan triangle i, seeded with the node itself (r2 = 0) and, if given, with `toward`;
  /// returns its best (r1, r2)
  std::array<double, 2> operator()(int i, const std::array<double, 2>* toward = nullptr) {
    static const std::vector<mga::Range> ranges{{0.0, 1.0}, {0.0, 0.5}};
    static const std::vector<std::vector<double>> nodeSeed1{{0.0, 0.0}};
    thread_local std::vector<std::vector<double>> seeds2{{0.0, 0.0}, {0.0, 0.0}};
    NodeSearch& ns = ns_;
    const Vec3 V2 = ns.M.X[std::size_t(fan_[std::size_t(i)].first)];
    const Vec3 V3 = ns.M.X[std::size_t(fan_[std::size_t(i)].second)];
    auto candidate = [&](const std::vector<double>& r) {
      return (1 - r[1]) * ns.x0 + r[1] * (1 - r[0]) * V2 + r[0] * r[1] * V3;
    };
    auto fitness = [&](const std::vector<double>& r) {
      if (r[1] <= 0) return ns.startFit;  // r2 = 0: the node itself, exactly
      if (onPlane_) {  // the candidate where it lies, with the node's normal
        ++ns.evaluations;
        return ns.fitness(candidate(r), ns.n0);
      }
      Vec3 P;
      Loc L;
      return ns.eval(candidate(r), P, L);
    };
    mga::Options o = mo_;
    o.seed = mga::itemSeed(nodeSeed_, std::uint64_t(i));
    o.recordHistory = false;
    if (toward) seeds2[1] = {(*toward)[0], (*toward)[1]};
    const mga::Result r = mga::optimize(ranges, fitness, o, toward ? seeds2 : nodeSeed1);
    if ((onPlane_ || r.fitness > ns.bestFit) && r.x[1] > 0) {
      Vec3 P;
      Loc L;
      const Vec3 q = candidate(r.x);
      ns.offer(ns.eval(q, P, L), P, L, q);
    }
    return std::array<double, 2>{r.x[0], r.x[1]};
  }

 private:
  NodeSearch& ns_;
  const Fan& fan_;
  const mga::Options& mo_;
  std::uint64_t nodeSeed_;
  bool onPlane_;
};

/// the centroid of the fan's corners other than the node, relative to the node
Vec3 neighbourCentroid(const Mesh& M, const Fan& fan, const Vec3& x0) {
  Vec3 c(0, 0, 0);
  for (const auto& f : fan) c += M.X[std::size_t(f.first)] + M.X[std::size_t(f.second)];
  return c / double(2 * fan.size()) - x0;
}

/// the first fan triangle whose sector (seen along the node's normal) holds the direction c (else 0)
int sectorOf(const NodeSearch& ns, const Fan& fan, const Vec3& c) {
  const int nf = int(fan.size());
  for (int i = 0; i < nf; ++i) {
    const Vec3 d2 = ns.M.X[std::size_t(fan[std::size_t(i)].first)] - ns.x0;
    const Vec3 d3 = ns.M.X[std::size_t(fan[std::size_t(i)].second)] - ns.x0;
    if (ns.n0.dot(d2.cross(c)) >= 0 && ns.n0.dot(c.cross(d3)) >= 0) return i;
  }
  return 0;
}

/// c as (r1, r2) of fan triangle i: c ~ a d2 + b d3 (least squares in the triangle's plane), r2 = a + b
/// (at most 0.5, the search's range), r1 = b / (a + b): the point tangential relaxation would move to;
/// (0, 0) if c is not ahead of the node in that triangle
std::array<double, 2> seedToward(const NodeSearch& ns, const Fan& fan, int i, const Vec3& c) {
  std::array<double, 2> toward{0.0, 0.0};
  const Vec3 d2 = ns.M.X[std::size_t(fan[std::size_t(i)].first)] - ns.x0;
  const Vec3 d3 = ns.M.X[std::size_t(fan[std::size_t(i)].second)] - ns.x0;
  const double g22 = d2.dot(d2), g23 = d2.dot(d3), g33 = d3.dot(d3), det = g22 * g33 - g23 * g23;
  if (det > 1e-12 * g22 * g33) {
    const double a = std::max(0.0, (g33 * d2.dot(c) - g23 * d3.dot(c)) / det);
    const double b = std::max(0.0, (g22 * d3.dot(c) - g23 * d2.dot(c)) / det);
    if (a + b > 0) toward = {b / (a + b), std::min(a + b, 0.5)};
  }
  return toward;
}

/// the other fan triangle than i with the edge (node, v); -1 if none
int across(const Fan& fan, int i, int v) {
  const int nf = int(fan.size());
  for (int j = 0; j < nf; ++j)
    if (j != i && (fan[std::size_t(j)].first == v || fan[std::size_t(j)].second == v)) return j;
  return -1;
}

/// thesis steps 3-7: the micro-GA inside each triangle around the node (a quad gives two), in the order
/// of Options::elementSearch.
void searchMga(NodeSearch& ns, const mga::Options& mo, std::uint64_t nodeSeed, ElementSearch mode) {
  thread_local Fan fan;  // buffers reused per thread
  gatherFan(ns.M, ns.n, fan);
  const int nf = int(fan.size());
  // GuidedLocal on a star that starts valid: the micro-GA measures its candidates on the triangle's plane
  // (no projection), and only each triangle's best is projected and measured on the surface; a folded or
  // invalid star, which needs the surface normal at every candidate to unfold, is searched on the surface
  const bool onPlane = mode == ElementSearch::GuidedLocal && ns.startFit >= 0;
  FanSearch search(ns, fan, mo, nodeSeed, onPlane);
  if (mode == ElementSearch::Every || nf < 2) {
    for (int i = 0; i < nf; ++i) search(i);
    return;
  }
  // Guided: start in the triangle whose sector (seen along the node's normal) holds the direction to
  // the centroid of the node's neighbours, with the centroid as a second seed there; while the best
  // point of a triangle lies on one of its two edges through the node (r1 within kEdgeR1 of 0 or 1), go
  // on into the triangle across that edge; stop at an optimum inside a triangle. A triangle where no move gains
  // (r2 ~ 0) sends the search to every triangle, as the thesis does (GuidedLocal: only if the star starts folded or
  // invalid; else the search ends there).
  constexpr double kEdgeR1 = 0.05;
  const Vec3 c = neighbourCentroid(ns.M, fan, ns.x0);
  int cur = sectorOf(ns, fan, c);
  const std::array<double, 2> towardC = seedToward(ns, fan, cur, c);
  const std::array<double, 2>* toward = towardC[1] > 0 ? &towardC : nullptr;
  thread_local std::vector<char> done;
  done.assign(std::size_t(nf), 0);
  while (cur >= 0 && !done[std::size_t(cur)]) {
    done[std::size_t(cur)] = 1;
    const auto x = search(cur, toward);
    toward = nullptr;  // the centroid seeds the start triangle only
    if (x[1] < 2 * mo.accuracy) {  // no gain in this triangle
      if (mode == ElementSearch::Guided || ns.startFit < 0)
        for (int i = 0; i < nf; ++i)
          if (!done[std::size_t(i)]) search(i);
      return;
    }
    cur = x[0] < kEdgeR1 ? across(fan, cur, fan[std::size_t(cur)].first)
        : x[0] > 1 - kEdgeR1 ? across(fan, cur, fan[std::size_t(cur)].second) : -1;
  }
}

/// The node's tangent plane as a local parametric frame: (u, v) -> x0 + h (u e1 + v e2), h the mean edge
/// length to the node's element neighbours. The fitness there is of the surface point nearest to the
/// frame's point, and each point measured is offered to the node's search.
struct TangentPlane {
  NodeSearch& ns;
  double h = 0;
  Vec3 e1, e2;

  /// the frame at the node; false if the node has no neighbour or no tangent direction
  bool build() {
    const Mesh& M = ns.M;
    int cnt = 0;
    Vec3 ref(0, 0, 0);
    for (int ei : M.vE[std::size_t(ns.n)]) {
      const Element& e = M.E[std::size_t(ei)];
      for (int k = 0; k < e.nv; ++k)
        if (e.v[k] != ns.n) {
          const Vec3 d = M.X[std::size_t(e.v[k])] - ns.x0;
          h += d.norm();
          ++cnt;
          if (ref.squaredNorm() == 0) ref = d;
        }
    }
    if (cnt == 0 || !(h > 0)) return false;
    h /= cnt;
    e1 = ref - ns.n0.dot(ref) * ns.n0;
    if (!(e1.norm() > 1e-12 * h)) return false;
    e1.normalize();
    e2 = ns.n0.cross(e1);
    return true;
  }
  Vec3 point(const Eigen::Vector2d& p) const { return Vec3(ns.x0 + h * (p.x() * e1 + p.y() * e2)); }
  double operator()(const Eigen::Vector2d& x) const {
    Vec3 P;
    Loc L;
    const Vec3 q = point(x);
    const double v = ns.eval(q, P, L);
    ns.offer(v, P, L, q);
    return v;
  }
  /// the gradient by central differences
  Eigen::Vector2d grad(const Eigen::Vector2d& x) const {
    const double delta = 1e-5;
    const TangentPlane& f = *this;
    Eigen::Vector2d g;
    for (int i = 0; i < 2; ++i) {
      Eigen::Vector2d a = x, b = x;
      a[i] += delta;
      b[i] -= delta;
      g[i] = (f(a) - f(b)) / (2 * delta);
    }
    return g;
  }
};

/// Line search along d from p (fitness fp): steps of at most half an edge length (amax), halved until
/// better; the best step and its fitness in (bestA, bestF), bestA = 0 if none gains.
void halvingSteps(const TangentPlane& f, const Eigen::Vector2d& p, const Eigen::Vector2d& d, double amax, double fp,
                  double& bestA, double& bestF) {
  bestA = 0;
  bestF = fp;
  for (int k = 0; k < 10; ++k) {
    const double a = amax * std::ldexp(1.0, -k);
    const double fa = f(p + a * d);
    if (fa > bestF) {
      bestF = fa;
      bestA = a;
    } else if (bestA > 0) {
      break;  // got worse again after an improvement: bracketed
    }
  }
}

/// The line search's refinement: a parabola through (a/2, a, 2a) where available; (bestA, bestF) become the
/// best of those points and the parabola's vertex.
void parabolaStep(const TangentPlane& f, const Eigen::Vector2d& p, const Eigen::Vector2d& d, double amax, double& bestA,
                  double& bestF) {
  const double a0 = bestA * 0.5, a2 = std::min(bestA * 2, amax);
  if (!(a2 > bestA)) return;
  const double f0 = f(p + a0 * d), f2 = f(p + a2 * d);
  // concave through (a0, f0), (a, f), (a2, f2) (second divided difference < 0): try its vertex
  if ((f2 - bestF) / (a2 - bestA) - (bestF - f0) / (bestA - a0) < 0) {
    const double num = (bestA - a0) * (bestA - a0) * (bestF - f2) - (bestA - a2) * (bestA - a2) * (bestF - f0);
    const double dd = (bestA - a0) * (bestF - f2) - (bestA - a2) * (bestF - f0);
    if (dd != 0) {
      const double av = bestA - 0.5 * num / dd;
      if (av > 0 && av <= amax) {
        const double fv = f(p + av * d);
        if (fv > bestF) bestF = fv, bestA = av;
      }
    }
  }
  if (f0 > bestF) bestF = f0, bestA = a0;
  if (f2 > bestF) bestF = f2, bestA = a2;
}

/// the baseline: Polak-Ribiere conjugate gradient ascent in the node's tangent plane (u, v)
void searchGradient(NodeSearch& ns, int iterations) {
  TangentPlane f{ns};
  if (!f.build()) return;
  Eigen::Vector2d p(0, 0);  // current point (the node: u = v = 0)
  double fp = ns.startFit;
  Eigen::Vector2d g = f.grad(p), d = g;
  for (int it = 0; it < iterations; ++it) {
    const double dn = d.norm();
    if (!(dn > 1e-9) || !g.allFinite()) break;
    // line search along d: steps of at most half an edge length, halved until better, then a parabola
    const double amax = 0.5 / dn;
    double bestA, bestF;
    halvingSteps(f, p, d, amax, fp, bestA, bestF);
    if (bestA <= 0) break;
    parabolaStep(f, p, d, amax, bestA, bestF);
    p += bestA * d;
    fp = bestF;
    const Eigen::Vector2d gn = f.grad(p);
    const double beta = std::max(0.0, gn.dot(gn - g) / std::max(g.squaredNorm(), 1e-300));  // Polak-Ribiere+
    d = gn + beta * d;
    if (d.dot(gn) <= 0) d = gn;  // not an ascent direction: restart with the gradient
    g = gn;
    if (g.norm() < 1e-8) break;
  }
}


// thesis step 1, the parameters: throws InputError naming the first one out of its range
void validateOptions(const Options& opt) {
  if (opt.population < kPopulationRange.lo)
    throw InputError("population must be at least " + std::to_string(int(kPopulationRange.lo)) + ", got " + std::to_string(opt.population));
  if (!kAccuracyRange.contains(opt.accuracy))
    throw InputError("accuracy must be in " + kAccuracyRange.text() + ", got " + std::to_string(opt.accuracy));
  if (opt.maxSweeps < kMaxSweepsRange.lo)
    throw InputError("maximum sweeps must be at least " + std::to_string(int(kMaxSweepsRange.lo)));
  if (opt.generations < kGenerationsRange.lo)
    throw InputError("generations per element must be at least " + std::to_string(int(kGenerationsRange.lo)));
  if (opt.restarts < kRestartsRange.lo) throw InputError("restarts must not be negative");
  if (!(opt.tolerance >= kToleranceRange.lo)) throw InputError("tolerance must not be negative");
  if (!kAngleRange.contains(opt.featureAngleDeg))
    throw InputError("feature angle must be in " + kAngleRange.text() + " degrees");
  if (!kQualityRange.contains(opt.worstGuard)) throw InputError("worst-element guard must be in " + kQualityRange.text());
  if (!kQualityRange.contains(opt.minPassBelow))
    throw InputError("final worst-element pass threshold must be in " + kQualityRange.text());
  if (opt.minPassSweeps < 0) throw InputError("final worst-element pass sweeps must not be negative");
  if (!kAngleRange.contains(opt.singularAngleDeg))
    throw InputError("singular angle must be in " + kAngleRange.text() + " degrees");
  if (opt.method == Method::ConjugateGradient && !kCgIterationsRange.contains(opt.cgIterations))
    throw InputError("conjugate gradient iterations must be in " + kCgIterationsRange.text(true) + ", got " +
                     std::to_string(opt.cgIterations));
}

// the mesh the sweeps move: tm's compact nodes (toM: node -> m.vert index) and em's elements on them
Mesh buildMesh(const c1::TriMesh& tm, const std::vector<int>& toM, const ElementMesh& em, std::size_t mVerts) {
  std::vector<int> toC(mVerts, -1);
  for (std::size_t i = 0; i < toM.size(); ++i) toC[std::size_t(toM[i])] = int(i);
  Mesh M;
  M.X = tm.V;
  M.E = em.elements;
  for (auto& e : M.E)
    for (int k = 0; k < e.nv; ++k) e.v[k] = toC[std::size_t(e.v[k])];
  M.vE.assign(tm.V.size(), {});
  for (int i = 0; i < int(M.E.size()); ++i)
    for (int k = 0; k < M.E[std::size_t(i)].nv; ++k) M.vE[std::size_t(M.E[std::size_t(i)].v[k])].push_back(i);
  return M;
}

/// The nodes that stay where they are, by kind (a node can be of several kinds)
struct NodeKinds {
  std::vector<char> boundary, feature, singular;
  std::size_t creaseChains = 0;  ///< Creases: chains found
  std::string featureSummary;    ///< Creases: Creases::summary()
};

// unit normal of every face of tm (zero for a face without area)
std::vector<Vec3> unitFaceNormals(const c1::TriMesh& tm) {
  std::vector<Vec3> fn(tm.F.size());
  for (std::size_t f = 0; f < tm.F.size(); ++f) {
    const auto& F = tm.F[f];
    const Vec3 n = (tm.V[std::size_t(F[1])] - tm.V[std::size_t(F[0])]).cross(tm.V[std::size_t(F[2])] - tm.V[std::size_t(F[0])]);
    fn[f] = n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 0);
  }
  return fn;
}

// the diagonals of the quad elements (the faux edges inside quads, which are not feature edges), sorted
std::vector<std::uint64_t> quadDiagonals(const Mesh& M) {
  std::vector<std::uint64_t> diagonals;
  for (const auto& e : M.E)
    if (e.nv == 4) {
      diagonals.push_back(edgeKey(e.v[0], e.v[2]));
      diagonals.push_back(edgeKey(e.v[1], e.v[3]));
    }
  std::sort(diagonals.begin(), diagonals.end());
  return diagonals;
}

// Angles: the nodes of every edge (not a quad diagonal) whose faces' normals differ by more than the
// feature angle
void sharpEdgeNodes(const C1Surface& S, const std::vector<Vec3>& fn, const std::vector<std::uint64_t>& diagonals,
                    double featureAngleDeg, std::vector<char>& feature) {
  const double cosLim = std::cos(featureAngleDeg * M_PI / 180.0);
  for (const auto& e : S.edges()) {
    if (e.f1 >= 0 && featureAngleDeg < 180 && !std::binary_search(diagonals.begin(), diagonals.end(), edgeKey(e.a, e.b))) {
      const Vec3& a = fn[std::size_t(e.f0)];
      const Vec3& b = fn[std::size_t(e.f1)];
      if (a.squaredNorm() > 0 && b.squaredNorm() > 0 && a.dot(b) < cosLim)
        feature[std::size_t(e.a)] = feature[std::size_t(e.b)] = 1;
    }
  }
}

// Angles: the nodes whose faces' normal cone (the largest angle between two of their normals) is wider
// than the singular angle: large curvature variation within one ring (thesis 4.3)
void wideConeNodes(const Topology& T, const std::vector<Vec3>& fn, double singularAngleDeg, std::vector<char>& singular) {
  const std::vector<int>& start = T.vfStart;
  const std::vector<int>& vf = T.vf;
  const std::size_t nv = start.size() - 1;
  const double cosSing = std::cos(singularAngleDeg * M_PI / 180.0);
  for (std::size_t i = 0; i < nv; ++i) {
    for (int a = start[i]; a < start[i + 1] && !singular[i]; ++a) {
      const Vec3& na = fn[std::size_t(vf[std::size_t(a)])];
      if (!(na.squaredNorm() > 0)) continue;
      for (int b = a + 1; b < start[i + 1]; ++b) {
        const Vec3& nb = fn[std::size_t(vf[std::size_t(b)])];
        if (nb.squaredNorm() > 0 && na.dot(nb) < cosSing) {
          singular[i] = 1;
          break;
        }
      }
    }
  }
}

// boundary nodes, and feature and singular nodes by opt.features: the crease chains and their corners,
// or the feature and singular angles
NodeKinds classifyNodes(const c1::TriMesh& tm, const Mesh& M, const C1Surface& S, const Options& opt) {
  const std::size_t nv = tm.V.size();
  NodeKinds nk;
  nk.boundary.assign(nv, 0), nk.feature.assign(nv, 0), nk.singular.assign(nv, 0);
  const std::vector<Vec3> fn = unitFaceNormals(tm);
  const std::vector<std::uint64_t> diagonals = quadDiagonals(M);
  for (const auto& e : S.edges())
    if (e.f1 < 0) nk.boundary[std::size_t(e.a)] = nk.boundary[std::size_t(e.b)] = 1;
  if (opt.features == FeatureDetection::Creases) {
    // crease chains told from noise (creases.h); their corners are the singular points
    const Creases cr = detectCreases(tm.V, tm.F, S.topology(), diagonals);
    for (std::size_t i = 0; i < nv; ++i) {
      nk.feature[i] = cr.node[i] && !cr.corner[i];
      nk.singular[i] = cr.corner[i];
    }
    nk.creaseChains = cr.chains.size();
    nk.featureSummary = cr.summary();
  } else {
    sharpEdgeNodes(S, fn, diagonals, opt.featureAngleDeg, nk.feature);
  }
  if (opt.features == FeatureDetection::Angles && opt.singularAngleDeg < 180)
    wideConeNodes(S.topology(), fn, opt.singularAngleDeg, nk.singular);
  return nk;
}

// the fixed nodes (boundary, feature, singular, the user's, in no element), each counted into res under
// the first of those kinds; returns the free nodes, and throws InputError, naming the counts, if there is none
std::vector<int> freeNodesOf(const NodeKinds& nk, const Mesh& M, const std::vector<int>& toM,
                             const std::vector<char>& userFixed, const Options& opt, std::vector<char>& fixed,
                             Result& res) {
  const std::size_t nv = M.X.size();
  fixed.assign(nv, 0);
  for (std::size_t i = 0; i < nv; ++i) {
    const bool user = !userFixed.empty() && userFixed[std::size_t(toM[i])];
    if (nk.boundary[i]) ++res.boundaryNodes;
    else if (nk.feature[i]) ++res.featureNodes;
    else if (nk.singular[i]) ++res.singularNodes;
    else if (user) ++res.userFixedNodes;
    fixed[i] = nk.boundary[i] || nk.feature[i] || nk.singular[i] || user || M.vE[i].empty();
  }
  std::vector<int> freeNodes;
  for (std::size_t i = 0; i < nv; ++i)
    if (!fixed[i]) freeNodes.push_back(int(i));
  if (freeNodes.empty())
    throw InputError("no free node to smooth: all " + std::to_string(nv) + " vertices are fixed (" +
                     std::to_string(res.boundaryNodes) + " boundary, " + std::to_string(res.featureNodes) +
                     " on feature edges, " + std::to_string(res.singularNodes) + " singular, " +
                     std::to_string(res.userFixedNodes) +
                     " by the selection)" +
                     (opt.features == FeatureDetection::Angles
                          ? std::string("; raise the feature or singular angle or change the selection mode")
                      : res.featureNodes + res.singularNodes > 0
                          ? "; feature detection found " + nk.featureSummary +
                                "; choose feature detection by angles, or change the selection mode"
                          : std::string("; change the selection mode")));
  return freeNodes;
}

// every node's start location on the surface: its corner of the first face it is in
std::vector<Loc> cornerLocations(const c1::TriMesh& tm) {
  std::vector<Loc> loc(tm.V.size());
  for (int f = 0; f < int(tm.F.size()); ++f)
    for (int k = 0; k < 3; ++k) {
      Loc& L = loc[std::size_t(tm.F[std::size_t(f)][std::size_t(k)])];
      if (L.face >= 0) continue;
      L.face = f;
      L.s = k == 1 ? 1 : 0;
      L.t = k == 2 ? 1 : 0;
    }
  return loc;
}

// greedy colouring of the free nodes in index order: nodes sharing an element get different colours, so
// the nodes of one colour can move in parallel; returns the nodes of each colour
std::vector<std::vector<int>> colourClasses(const Mesh& M, const std::vector<int>& freeNodes) {
  std::vector<int> colour(M.X.size(), -1);
  std::vector<std::vector<int>> classes;
  for (int n : freeNodes) {
    std::vector<char> used(classes.size() + 1, 0);
    for (int ei : M.vE[std::size_t(n)])
      for (int k = 0; k < M.E[std::size_t(ei)].nv; ++k) {
        const int c = colour[std::size_t(M.E[std::size_t(ei)].v[k])];
        if (c >= 0) used[std::size_t(c)] = 1;
      }
    int c = 0;
    while (used[std::size_t(c)]) ++c;
    colour[std::size_t(n)] = c;
    if (c == int(classes.size())) classes.emplace_back();
    classes[std::size_t(c)].push_back(n);
  }
  return classes;
}

/// The sweeps over the free nodes (thesis steps 2-9): the colours one after the other, the nodes of a
/// colour in parallel, each searched from where it is and moved to its best point on the C1 surface; then
/// the colour's moves are kept one after the other, each only if it folds no element (folds.h) that was
/// not folded before it.
class Sweeps {
 public:
  Sweeps(Mesh& M, std::vector<Loc>& loc, const C1Surface& S, const Projector& proj, const Options& opt,
         const std::vector<int>& toM, const std::vector<std::vector<int>>& classes, const std::vector<int>& freeNodes,
         const std::vector<char>& fixed, const Folds& folds)
      : M_(M), loc_(loc), S_(S), proj_(proj), opt_(opt), toM_(toM), classes_(classes), freeNodes_(freeNodes),
        fixed_(fixed), folds_(folds), projDist_(M.X.size(), 0.0), evaluations_(M.X.size(), 0), active_(M.X.size(), 0),
        gained_(M.X.size(), 0), from_(M.X.size()), normal_(folds.normals(M.X)), seen_(M.E.size(), 0) {
    mo_.population = opt.population;
    mo_.accuracy = opt.accuracy;
    mo_.maxRestarts = opt.restarts;
    mo_.maxGenerations = opt.generations;
    mo_.selection = opt.selection;
    for (int n : freeNodes) active_[std::size_t(n)] = 1;
  }

  /// the sweeps until the mean quality gains less than the tolerance, no node is active, the sweep cap
  /// or the progress callback stops them; then the optional final max-min pass (not after a stop)
  void run(Result& res) {
    double mean = res.before.mean;
    bool stopped = false;
    for (int sweep = 0; sweep < opt_.maxSweeps; ++sweep) {
      sweepOnce(sweep, false);
      res.sweeps = sweep + 1;
      res.searches += std::size_t(std::count(active_.begin(), active_.end(), char(1)));
      const std::size_t nActive = opt_.activeSet ? nextActiveSet() : freeNodes_.size();
      const double newMean = stats(M_).mean;
      const double gain = newMean - mean;
      mean = newMean;
      if (opt_.progress && !opt_.progress(sweep + 1, mean)) {
        stopped = true;
        break;
      }
      if (gain < opt_.tolerance || nActive == 0) break;
    }
    if (opt_.minPassBelow > 0 && !stopped)
      for (int k = 0; k < opt_.minPassSweeps; ++k) {
        const double before = stats(M_).min;
        sweepOnce(opt_.maxSweeps + k, true);
        ++res.minPassSweeps;
        if (stats(M_).min <= before) break;
      }
  }

  std::size_t evaluations() const { return std::accumulate(evaluations_.begin(), evaluations_.end(), std::size_t(0)); }
  /// moves undone because they folded an element
  std::size_t movesUndone() const { return movesUndone_; }
  double maxProjectionDistance() const { return *std::max_element(projDist_.begin(), projDist_.end()); }

 private:
  // one sweep over the free nodes; maxMin: only nodes whose worst element is below opt.minPassBelow,
  // maximising that worst element
  void sweepOnce(int sweep, bool maxMin) {
    const std::uint64_t sweepSeed = mga::itemSeed(opt_.seed, std::uint64_t(sweep));
    for (const auto& cls : classes_) {
      for (int n : cls)
        from_[std::size_t(n)] = From{M_.X[std::size_t(n)], M_.N[std::size_t(n)], loc_[std::size_t(n)], projDist_[std::size_t(n)]};
#pragma omp parallel for schedule(dynamic, 8)
      for (int ci = 0; ci < int(cls.size()); ++ci) {
        const int n = cls[std::size_t(ci)];
        if (!maxMin && !active_[std::size_t(n)]) continue;
        searchNode(n, maxMin, sweepSeed);
      }
      keepUnfolding(cls);
    }
  }

  // The moves of one colour, taken again one after the other in node order from where the colour started;
  // a move that folds an element (Folds) that was not folded before it is undone. The fold test of an
  // element reads the nodes of its edge neighbours too, which may share the colour: hence in order, after
  // the parallel search. A folded element can unfold, and no element folds anew. The elements' unit normals
  // are kept (normal_): a move changes those of the node's own elements only.
  void keepUnfolding(const std::vector<int>& cls) {
    std::vector<int> moved;
    for (int n : cls)
      if (M_.X[std::size_t(n)] != from_[std::size_t(n)].x) moved.push_back(n);
    std::vector<Vec3> to(moved.size());
    for (std::size_t i = 0; i < moved.size(); ++i) {
      to[i] = M_.X[std::size_t(moved[i])];
      M_.X[std::size_t(moved[i])] = from_[std::size_t(moved[i])].x;
    }
    std::vector<int> readers;
    std::vector<char> before;
    std::vector<Vec3> oldNormal;
    const auto kept = [&](int g) -> const Vec3& { return normal_[std::size_t(g)]; };
    for (std::size_t i = 0; i < moved.size(); ++i) {
      const int n = moved[i];
      const std::vector<int>& star = M_.vE[std::size_t(n)];
      // the elements whose fold test reads n (its own and their edge neighbours, each once), and their
      // state before the move
      ++stamp_;
      readers.clear();
      const auto list = [&](int r) {
        if (seen_[std::size_t(r)] != stamp_) seen_[std::size_t(r)] = stamp_, readers.push_back(r);
      };
      for (int e : star) {
        list(e);
        for (int g : folds_.neighbours(e)) list(g);
      }
      before.resize(readers.size());
      for (std::size_t k = 0; k < readers.size(); ++k) before[k] = folds_.foldedBy(readers[k], kept);
      // the move: its elements' normals change, the others' do not
      M_.X[std::size_t(n)] = to[i];
      oldNormal.resize(star.size());
      for (std::size_t k = 0; k < star.size(); ++k) {
        oldNormal[k] = normal_[std::size_t(star[k])];
        normal_[std::size_t(star[k])] = elementNormal(M_.E[std::size_t(star[k])], M_.X);
      }
      bool folds = false;
      for (std::size_t k = 0; k < readers.size() && !folds; ++k) folds = !before[k] && folds_.foldedBy(readers[k], kept);
      if (!folds) continue;
      for (std::size_t k = 0; k < star.size(); ++k) normal_[std::size_t(star[k])] = oldNormal[k];
      const From& f = from_[std::size_t(n)];
      M_.X[std::size_t(n)] = f.x;
      M_.N[std::size_t(n)] = f.normal;
      loc_[std::size_t(n)] = f.loc;
      projDist_[std::size_t(n)] = f.projDist;
      gained_[std::size_t(n)] = 0;
      ++movesUndone_;
    }
  }

  // node n's search (the micro-GA or the gradient baseline) and its move
  void searchNode(int n, bool maxMin, std::uint64_t sweepSeed) {
    const Vec3 x0 = M_.X[std::size_t(n)];
    const Loc l0 = loc_[std::size_t(n)];
    const Vec3 n0 = M_.N[std::size_t(n)];
    double curMin = 0;
    const double cap = maxMin ? opt_.minPassBelow : 0.0;
    thread_local TriStar star;
    const bool haveStar = star.gather(M_, n);
    double fit0 = haveStar ? star.fitness(x0, n0, -1.0, cap, &curMin) : fitnessAt(M_, n, x0, n0, -1.0, cap, &curMin);
    if (maxMin && !(curMin < opt_.minPassBelow)) return;
    // the node's worst element may not drop below min(its current value, the guard level)
    const double guard = std::min(curMin, opt_.worstGuard);
    if (fit0 >= 0) fit0 = haveStar ? star.fitness(x0, n0, guard, cap) : fitnessAt(M_, n, x0, n0, guard, cap);
    NodeSearch ns{M_, proj_, n, x0, n0, l0, guard, cap, fit0, fit0, x0, l0};
    ns.star = haveStar ? &star : nullptr;
    if (opt_.method == Method::MicroGA) {
      ns.linTol = kSearchLinTol;
      searchMga(ns, mo_, mga::itemSeed(sweepSeed, std::uint64_t(toM_[std::size_t(n)])), opt_.elementSearch);
    } else {
      searchGradient(ns, opt_.cgIterations);  // exact projections: its finite differences need them
    }
    evaluations_[std::size_t(n)] += ns.evaluations;
    // the move: the surface point exactly at the best location (the search's candidates may be off
    // the patch to first order, see kSearchLinTol), taken only if its fitness there still gains
    Vec3 nrm = n0;
    if (ns.bestFit > fit0) {
      const Loc& b = ns.bestLoc;
      const c1::SurfacePoint sp = S_.at(b.face, Vec3(1 - b.s - b.t, b.s, b.t));
      const double f = ns.fitness(sp.point, sp.normal);
      if (f > fit0) {
        ns.bestX = sp.point;
        ns.bestFit = f;
        nrm = sp.normal;
      } else {
        ns.bestX = x0;
        ns.bestLoc = l0;
        ns.bestFit = fit0;
        ns.bestDist = 0;
      }
    }
    // the node moves after its own search: neighbours of the same colour do not see it, and
    // no node of this colour reads it (they share no element)
    M_.X[std::size_t(n)] = ns.bestX;
    M_.N[std::size_t(n)] = nrm;
    loc_[std::size_t(n)] = ns.bestLoc;
    projDist_[std::size_t(n)] = std::max(projDist_[std::size_t(n)], ns.bestDist);
    if (!maxMin) gained_[std::size_t(n)] = ns.bestFit - fit0 > opt_.tolerance * double(M_.vE[std::size_t(n)].size());
  }

  // the active set of the next sweep: the free nodes of the elements of every node that gained more than
  // the tolerance x (its number of elements) in its last search; returns their number
  std::size_t nextActiveSet() {
    const std::size_t nv = M_.X.size();
    std::fill(active_.begin(), active_.end(), 0);
    for (std::size_t i = 0; i < nv; ++i)
      if (gained_[i])
        for (int ei : M_.vE[i])
          for (int k = 0; k < M_.E[std::size_t(ei)].nv; ++k) active_[std::size_t(M_.E[std::size_t(ei)].v[k])] = 1;
    std::fill(gained_.begin(), gained_.end(), 0);
    std::size_t nActive = 0;
    for (std::size_t i = 0; i < nv; ++i) {
      if (fixed_[i]) active_[i] = 0;
      nActive += active_[i];
    }
    return nActive;
  }

  Mesh& M_;
  std::vector<Loc>& loc_;
  const C1Surface& S_;
  const Projector& proj_;
  const Options& opt_;
  const std::vector<int>& toM_;
  const std::vector<std::vector<int>>& classes_;
  const std::vector<int>& freeNodes_;
  const std::vector<char>& fixed_;
  const Folds& folds_;
  mga::Options mo_;
  std::vector<double> projDist_;         ///< per node: the largest candidate-to-surface distance of its moves
  std::vector<std::size_t> evaluations_; ///< per node: fitness evaluations
  std::vector<char> active_, gained_;    ///< per node: searched in the next sweep; gained in its last search
  struct From {                          ///< a node's state before its colour's search (keepUnfolding)
    Vec3 x, normal;
    Loc loc;
    double projDist = 0;
  };
  std::vector<From> from_;
  std::vector<Vec3> normal_;             ///< per element: its unit normal where the nodes are (keepUnfolding)
  std::vector<unsigned> seen_;           ///< per element: the stamp of the last check that listed it
  unsigned stamp_ = 0;
  std::size_t movesUndone_ = 0;
};

// puts the moved nodes of elements back to their input positions (and input normals N0), round after round:
// in each, `flagged(X)` names the elements to mend and `around(e, nodes)` adds the elements whose nodes go
// back for e. Ends when a round puts nothing back: at the latest at the input, which flags nothing.
// Returns how many nodes were put back
template <class Flagged, class Around>
std::size_t putBack(Mesh& M, const std::vector<Vec3>& input, const std::vector<Vec3>& N0, Flagged flagged,
                    Around around) {
  std::size_t back = 0;
  for (bool changed = true; changed;) {
    changed = false;
    const std::vector<char> now = flagged(M.X);
    std::vector<int> elements;
    for (int e = 0; e < int(now.size()); ++e) {
      if (!now[std::size_t(e)]) continue;
      elements.clear();
      around(e, elements);
      for (int g : elements) {
        const Element& el = M.E[std::size_t(g)];
        for (int k = 0; k < el.nv; ++k) {
          const std::size_t v = std::size_t(el.v[std::size_t(k)]);
          if (M.X[v] == input[v]) continue;
          M.X[v] = input[v];
          M.N[v] = N0[v];
          ++back;
          changed = true;
        }
      }
    }
  }
  return back;
}

// folds the input did not have: the element and its edge neighbours (whose normals its test reads) go back
std::size_t putBackFolds(Mesh& M, const Folds& folds, const std::vector<char>& foldedInput,
                         const std::vector<Vec3>& input, const std::vector<Vec3>& N0) {
  return putBack(
      M, input, N0,
      [&](const std::vector<Vec3>& X) {
        std::vector<char> f = folds.all(X);
        for (std::size_t e = 0; e < f.size(); ++e) f[e] = f[e] && !foldedInput[e];
        return f;
      },
      [&](int e, std::vector<int>& out) {
        out = folds.neighbours(e);
        out.push_back(e);
      });
}

// elements below `floor` (min(the input's worst, the guard)): the sweeps keep every element there or above,
// and the nodes put back beside moved ones must too
std::size_t putBackBelow(Mesh& M, double floor, const std::vector<Vec3>& input, const std::vector<Vec3>& N0) {
  return putBack(
      M, input, N0,
      [&](const std::vector<Vec3>& X) {
        const std::vector<double> q = elementQualities(M.E, X);
        std::vector<char> f(q.size());
        for (std::size_t e = 0; e < q.size(); ++e) f[e] = q[e] < floor;
        return f;
      },
      [](int e, std::vector<int>& out) { out.push_back(e); });
}

// undoes the moves that make the surface cross itself (restoreCrossings); the nodes put back get their
// input normals N0 again. Returns how many were put back
std::size_t putBackCrossings(Mesh& M, const std::vector<Vec3>& input, const std::vector<Vec3>& N0) {
  std::vector<std::vector<int>> faces;
  faces.reserve(M.E.size());
  for (const Element& e : M.E) faces.emplace_back(e.v.begin(), e.v.begin() + e.nv);
  const std::vector<int> back = restoreCrossings(faces, input, M.X);
  for (int n : back) M.N[std::size_t(n)] = N0[std::size_t(n)];
  return back.size();
}

// the smoothed positions per m.vert index (deleted vertices unchanged), the nodes moved and the quality per face
void collectPositions(const CMeshO& m, const Mesh& M, const c1::TriMesh& tm, const std::vector<int>& toM, Result& res) {
  res.positions.resize(m.vert.size());
  for (std::size_t i = 0; i < m.vert.size(); ++i)
    res.positions[i] = Vec3(m.vert[i].cP()[0], m.vert[i].cP()[1], m.vert[i].cP()[2]);
  for (std::size_t i = 0; i < tm.V.size(); ++i) {
    if (M.X[i] != tm.V[i]) ++res.nodesMoved;
    res.positions[std::size_t(toM[i])] = M.X[i];
  }
  res.perFace = spreadToFaces(M.E, elementQualities(M.E, M.X), m.face.size());
}

}  // namespace

std::vector<int> restoreCrossings(const std::vector<std::vector<int>>& faces, const std::vector<Vec3>& before,
                                  std::vector<Vec3>& after) {
  std::vector<std::array<int, 3>> tris;
  for (const auto& f : faces) {
    tris.push_back({f[0], f[1], f[2]});
    if (f.size() == 4) tris.push_back({f[0], f[2], f[3]});
  }
  // one full check of the result; after that only the faces of the nodes put back can cross anew, and
  // only the faces of crossing pairs are looked up in the input (whose own crossings are left as they are)
  SelfIntersections crossings(before.size(), tris);
  std::vector<FacePair> now = crossings(after);
  if (now.empty()) return {};
  std::vector<std::vector<int>> trisOf(before.size());
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int v : tris[t]) trisOf[std::size_t(v)].push_back(int(t));
  std::set<std::pair<int, int>> inInput;
  std::vector<char> lookedUp(tris.size(), 0);
  std::vector<int> back;
  for (;;) {  // each round puts back at least one node, so this ends (at the latest with the input)
    std::vector<int> toLookUp;
    for (const FacePair& p : now)
      for (int t : {p.a, p.b})
        if (!lookedUp[std::size_t(t)]) lookedUp[std::size_t(t)] = 1, toLookUp.push_back(t);
    if (!toLookUp.empty())
      for (const FacePair& p : crossings.involving(toLookUp, before)) inInput.insert(std::minmax(p.a, p.b));
    std::vector<int> changed;
    for (const FacePair& p : now) {
      if (inInput.count(std::minmax(p.a, p.b))) continue;
      for (int t : {p.a, p.b})
        for (int v : tris[std::size_t(t)])
          if (after[std::size_t(v)] != before[std::size_t(v)]) {
            after[std::size_t(v)] = before[std::size_t(v)];
            back.push_back(v);
            changed.insert(changed.end(), trisOf[std::size_t(v)].begin(), trisOf[std::size_t(v)].end());
          }
    }
    if (changed.empty()) break;
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    now = crossings.involving(changed, after);
  }
  std::sort(back.begin(), back.end());
  return back;
}

Result smoothMesh(const CMeshO& m, const Options& opt, const std::vector<char>& userFixed) {
  const auto t0 = std::chrono::steady_clock::now();
  validateOptions(opt);
  requireMesh(m, MeshRequirements(), "input");  // faces, finite; the C1 surface refuses non-manifold meshes

  // the C1 surface of the original mesh, built once (its topology refuses a non-manifold mesh and gives
  // the edges for the fixed nodes and the creases), then the nodes and the elements on them
  std::vector<int> toM;
  const c1::TriMesh tm = pectus::surfaceOf(m, {}, &toM);
  C1Surface S(tm);
  const ElementMesh em = buildElements(m, opt.kind);
  Mesh M = buildMesh(tm, toM, em, m.vert.size());
  Result res;
  res.elements = M.E.size();
  res.quads = em.quads();

  std::vector<char> fixed;
  const NodeKinds kinds = classifyNodes(tm, M, S, opt);
  res.creaseChains = kinds.creaseChains;
  res.featureSummary = kinds.featureSummary;
  const std::vector<int> freeNodes = freeNodesOf(kinds, M, toM, userFixed, opt, fixed, res);
  res.freeNodes = freeNodes.size();
  res.before = stats(M);

  // every node on the surface: its location, and the surface normal there
  S.buildIndex();
  const Projector proj(S);
  std::vector<Loc> loc = cornerLocations(tm);
  M.N.resize(tm.V.size());
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < tm.V.size(); ++i) M.N[i] = normalAt(S, loc[i]);

  const std::vector<std::vector<int>> classes = colourClasses(M, freeNodes);
  res.colours = int(classes.size());
  const Folds folds(M.E, M.X.size());
  const std::vector<char> foldedInput = folds.all(M.X);
  res.foldsBefore = std::size_t(std::count(foldedInput.begin(), foldedInput.end(), char(1)));
  Sweeps sweeps(M, loc, S, proj, opt, toM, classes, freeNodes, fixed, folds);
  res.foldedBefore = foldedElements(M);
  const std::vector<Vec3> N0 = M.N;  // the input's normals, for the nodes restoreCrossings puts back
  res.setupSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  sweeps.run(res);

  // the surface must not cross itself where the input did not, nor fold, nor fall below the worst element
  // the sweeps keep: put back until none of these happens
  const double floor = std::min(res.before.min, opt.worstGuard);
  for (;;) {
    res.nodesPutBack += putBackCrossings(M, tm.V, N0);
    const std::size_t folded = putBackFolds(M, folds, foldedInput, tm.V, N0);
    const std::size_t poor = putBackBelow(M, floor, tm.V, N0);
    res.nodesPutBackFolds += folded;
    res.nodesPutBackGuard += poor;
    if (folded + poor == 0) break;
  }
  res.after = stats(M);
  res.foldedAfter = foldedElements(M);
  const std::vector<char> foldedOutput = folds.all(M.X);
  for (std::size_t e = 0; e < foldedOutput.size(); ++e) {
    res.foldsAfter += foldedOutput[e];
    res.foldsNew += foldedOutput[e] && !foldedInput[e];
  }
  res.movesUndoneForFolds = sweeps.movesUndone();
  res.evaluations = sweeps.evaluations();
  res.maxProjectionDistance = sweeps.maxProjectionDistance();
  collectPositions(m, M, tm, toM, res);
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace pectus::smooth
