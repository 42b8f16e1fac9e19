// Goodman-Said C1 surface: topology checks, vertex gradients (thesis eqs. 3-1..3-5, a quadratic fit or
// the global minimum-curvature estimate),
// control nets (eqs. 3-9..3-15, b111 re-derived below), evaluation with the rational blend (eq. 3-16).
#include "pectus/c1/surface.h"

#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

#include "c1_internal.h"
#include "pectus/errors.h"

namespace pectus::c1 {

namespace {

// value and first partials with respect to (s, t): forward-mode automatic differentiation
struct J {
  double v, s, t;
  J() {}  // uninitialized: every J is assigned before use
  J(double v_, double s_ = 0, double t_ = 0) : v(v_), s(s_), t(t_) {}
};
inline J operator+(J a, J b) { return {a.v + b.v, a.s + b.s, a.t + b.t}; }
inline J operator-(J a, J b) { return {a.v - b.v, a.s - b.s, a.t - b.t}; }
inline J operator*(J a, J b) { return {a.v * b.v, a.s * b.v + a.v * b.s, a.t * b.v + a.v * b.t}; }
inline J operator*(double k, J a) { return {k * a.v, k * a.s, k * a.t}; }
inline J operator/(J a, J b) {
  const double iv = 1.0 / b.v;
  return {a.v * iv, (a.s * b.v - a.v * b.s) * iv * iv, (a.t * b.v - a.v * b.t) * iv * iv};
}

std::pair<Vec3, Vec3> completeFrame(const Vec3& f) {
  const Vec3 a = std::abs(f.x()) < 0.6 ? Vec3(1, 0, 0) : (std::abs(f.y()) < 0.6 ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
  const Vec3 e1 = (a - a.dot(f) * f).normalized();
  return {e1, f.cross(e1)};
}

}  // namespace

Vec3 PatchJet::normal() const {
  const Vec3 n = Ps.cross(Pt);
  const double l = n.norm();
  return l > 0 && std::isfinite(l) ? Vec3(n / l) : Vec3(0, 0, 0);
}

// ------------------------------------------------------------------------------------------------
// topology

Topology checkedTopology(const TriMesh& m) {
  Topology topo(m);
  const int nv = int(m.V.size());
  if (topo.badFace >= 0) {
    std::ostringstream s;
    s << "face " << topo.badFace << " uses vertex index " << topo.badIndex << ", but the mesh has " << nv << " vertices";
    throw TopologyError(s.str());
  }
  for (int i = 0; i < nv; ++i)
    if (!m.V[std::size_t(i)].allFinite()) {
      std::ostringstream s;
      s << "vertex " << i << " has a NaN/Inf coordinate; remove it (Cleaning: Remove Unreferenced / fix the source)";
      throw InputError(s.str());
    }
  for (int e = 0; e < int(topo.edges.size()); ++e) {
    if (topo.edges[std::size_t(e)].faces <= 2) continue;
    const int* first = topo.edgeFacesBegin(e);
    const int* last = topo.edgeFacesEnd(e);
    auto sorted = [&](int f) {
      std::array<int, 3> v{m.F[std::size_t(f)][0], m.F[std::size_t(f)][1], m.F[std::size_t(f)][2]};
      std::sort(v.begin(), v.end());
      return v;
    };
    std::ostringstream s;
    for (const int* p = first; p != last; ++p)
      for (const int* q = p + 1; q != last; ++q)
        if (sorted(*p / 3) == sorted(*q / 3)) {
          s << "faces " << *p / 3 << " and " << *q / 3
            << " are duplicates (the same three vertices); remove them first (Cleaning: Remove Duplicate Faces)";
          throw TopologyError(s.str());
        }
    s << "edge (" << topo.edges[std::size_t(e)].a << ", " << topo.edges[std::size_t(e)].b << ") is shared by "
      << topo.edges[std::size_t(e)].faces << " faces (non-manifold edge); repair the mesh first (Cleaning: Repair non Manifold Edges)";
    throw TopologyError(s.str());
  }
  for (int i = 0; i < nv; ++i)
    if (topo.nonManifoldVertex[std::size_t(i)]) {
      const int nfv = topo.vfStart[std::size_t(i) + 1] - topo.vfStart[std::size_t(i)];
      std::ostringstream s;
      s << "vertex " << i << " is non-manifold (its " << nfv << " faces form more than one fan); repair the "
        << "mesh first (Cleaning: Repair non Manifold Vertices by splitting)";
      throw TopologyError(s.str());
    }
  return topo;
}

// ------------------------------------------------------------------------------------------------

C1Surface::~C1Surface() = default;
C1Surface::C1Surface(C1Surface&&) noexcept = default;
C1Surface& C1Surface::operator=(C1Surface&&) noexcept = default;

C1Surface::C1Surface(TriMesh mesh, const Options& opt) : mesh_(std::move(mesh)), opt_(opt) { build(nullptr); }

C1Surface::C1Surface(TriMesh mesh, std::vector<Vec3> normals, const Options& opt)
    : mesh_(std::move(mesh)), opt_(opt) {
  if (normals.size() != mesh_.V.size()) throw InputError("C1Surface: one normal per vertex is needed");
  build(&normals);
}

std::pair<Vec3, Vec3> C1Surface::frameAxes() const { return completeFrame(opt_.axis); }

namespace {

// gradient of the facet plane in the frame (e1, e2, f): eqs. 3-3..3-5 with the frame coordinates
bool facetGradient(const Vec3& p1, const Vec3& p2, const Vec3& p3, const Vec3& e1, const Vec3& e2, const Vec3& f,
                   Vec2& g, double& projArea) {
  const Vec3 n = (p2 - p1).cross(p3 - p2);  // (alpha, beta, gamma) of eq. 3-4 in world coordinates
  const double a = n.dot(e1), b = n.dot(e2), c = n.dot(f);
  projArea = 0.5 * std::abs(c);
  if (!(std::abs(c) > 1e-12 * n.norm()) || !(std::abs(c) > 0)) return false;
  g = Vec2(-a / c, -b / c);
  return std::isfinite(g.x()) && std::isfinite(g.y());
}

// Global minimum-curvature gradients of heights z over the plane points xy (GradientMethod::MinimumCurvature).
// Minimizes  E(g) = sum_edges L^-1/2 * int_0^L p''(s)^2 ds,  p the cubic Hermite curve along the edge with
// p(0) = z_a, p(L) = z_b, p'(0) = d0 = e.g_a, p'(L) = d1 = e.g_b (e the unit edge direction):
//   int p''^2 = 4/L (d0^2 + d0 d1 + d1^2) - 12 D/L^2 (d0 + d1) + 12 D^2/L^3,   D = z_b - z_a.
// Zero for linear data, so linear data is reproduced. The normal equations are a sparse SPD 2n x 2n system;
// a tiny pull (1e-9 of the vertex block's trace) towards the per-vertex estimate g (in: per-vertex,
// out: global) keeps vertices without a non-degenerate pair of edge directions solvable. False (g left
// unchanged) if the factorization fails or the result is not finite.
bool minimumCurvatureGradients(const std::vector<Vec2>& xy, const std::vector<double>& z,
                               const std::vector<Topology::Edge>& edges, std::vector<Vec2>& g) {
  const int n = int(xy.size());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(edges.size() * 16 + 2 * std::size_t(n));
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * n);
  std::vector<double> trace(n, 0.0);
  for (const auto& E : edges) {
    const Vec2 d = xy[E.b] - xy[E.a];
    const double L = d.norm();
    if (!(L > 0) || !std::isfinite(L)) continue;
    const Vec2 e = d / L;
    const double w = 1.0 / std::sqrt(L), D = z[E.b] - z[E.a];
    const Eigen::Matrix2d ee = e * e.transpose();
    const int idx[2] = {E.a, E.b};
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 2; ++c) {
        const Eigen::Matrix2d blk = (r == c ? 8.0 : 4.0) * w / L * ee;  // d^2E/dg_r dg_c
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j) trip.emplace_back(2 * idx[r] + i, 2 * idx[c] + j, blk(i, j));
      }
      rhs.segment<2>(2 * idx[r]) += 12.0 * w * D / (L * L) * e;
      trace[idx[r]] += 8.0 * w / L;
    }
  }
  for (int v = 0; v < n; ++v) {
    const double mu = trace[v] > 0 ? 1e-9 * trace[v] : 1.0;
    for (int i = 0; i < 2; ++i) trip.emplace_back(2 * v + i, 2 * v + i, mu);
    rhs.segment<2>(2 * v) += mu * g[v];
  }
  Eigen::SparseMatrix<double> A(2 * n, 2 * n);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::VectorXd x = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !x.allFinite()) return false;
  for (int v = 0; v < n; ++v) g[v] = x.segment<2>(2 * v);
  return true;
}

}  // namespace

namespace {

// area-weighted face normals, and which faces are degenerate (no area or a repeated vertex)
std::vector<Vec3> faceNormals(const TriMesh& mesh, std::vector<char>& degen, std::size_t& degenerate) {
  const int nf = int(mesh.F.size());
  std::vector<Vec3> fn(nf);
  degen.assign(nf, 0);
  for (int f = 0; f < nf; ++f) {
    const auto& F = mesh.F[f];
    const Vec3 &a = mesh.V[F[0]], &b = mesh.V[F[1]], &c = mesh.V[F[2]];
    fn[f] = (b - a).cross(c - a);
    const double l2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    if (!(fn[f].norm() > 1e-12 * l2) || F[0] == F[1] || F[1] == F[2] || F[0] == F[2]) {
      degen[f] = 1;
      ++degenerate;
    }
  }
  return fn;
}

// Frame::HeightField needs every non-degenerate face to face the same way along the axis
void requireHeightField(const std::vector<Vec3>& fn, const std::vector<char>& degen, const Vec3& axis) {
  int pos = 0, neg = 0;
  for (std::size_t f = 0; f < fn.size(); ++f)
    if (!degen[f]) (fn[f].dot(axis) > 1e-12 * fn[f].norm() ? pos : neg) += 1;
  if (pos && neg)
    throw InputError("the mesh is not a height field over the chosen axis: " + std::to_string(std::min(pos, neg)) +
                     " of its faces are flipped or vertical when seen along the axis; use the 3D "
                     "(vertex normal) frame");
}

// What the per-vertex normal estimate reads: the mesh, its face normals, and the height-field frame
// (he1, he2, axis) when hf
struct VertexNormalInput {
  const TriMesh& mesh;
  const Topology& topo;
  const std::vector<Vec3>& fn;
  const std::vector<char>& degen;
  GradientMethod gradient;
  bool hf;
  Vec3 axis, he1, he2;
};

// the vertex frame (e1, e2, f): the height-field frame, or f the vertex's area-weighted normal (else its
// mean unit face normal); false where neither exists (a flat vertex)
bool vertexFrame(const VertexNormalInput& in, int v, Vec3& f, Vec3& e1, Vec3& e2) {
  if (in.hf) {
    f = in.axis; e1 = in.he1; e2 = in.he2;
    return true;
  }
  const Topology& topo = in.topo;
  Vec3 s(0, 0, 0), su(0, 0, 0);
  for (int q = topo.vfStart[v]; q < topo.vfStart[v + 1]; ++q)
    if (!in.degen[topo.vf[q]]) { s += in.fn[topo.vf[q]]; su += in.fn[topo.vf[q]].normalized(); }
  if (s.norm() > 1e-9 * su.norm() && s.norm() > 0) f = s.normalized();
  else if (su.norm() > 1e-6) f = su.normalized();
  else return false;
  std::tie(e1, e2) = completeFrame(f);
  return true;
}

// v's 2-ring neighbourhood, grown to the 3-ring where it has fewer than 8 points (corners, boundaries);
// each ring's new vertices in ascending order, v itself not included
std::vector<int> ringNeighbourhood(const VertexNormalInput& in, int v) {
  const int nv = int(in.mesh.V.size());
  // `seen` marks the vertices taken for v (a stamp per v)
  thread_local std::vector<unsigned> seen;
  thread_local unsigned stamp = 0;
  if (seen.size() < std::size_t(nv)) seen.assign(std::size_t(nv), 0u);
  if (++stamp == 0) {
    std::fill(seen.begin(), seen.end(), 0u);
    stamp = 1;
  }
  std::vector<int> nb{v};
  seen[std::size_t(v)] = stamp;
  std::size_t ringStart = 0;
  for (int ring = 0; ring < 3; ++ring) {
    if (ring == 2 && nb.size() >= 9) break;
    const std::size_t ringEnd = nb.size();
    for (std::size_t q0 = ringStart; q0 < ringEnd; ++q0) {
      const int w = nb[q0];
      for (int r = in.topo.vfStart[w]; r < in.topo.vfStart[w + 1]; ++r)
        for (int kk = 0; kk < 3; ++kk) {
          const int a = in.mesh.F[in.topo.vf[r]][kk];
          if (seen[std::size_t(a)] != stamp) {
            seen[std::size_t(a)] = stamp;
            nb.push_back(a);
          }
        }
    }
    std::sort(nb.begin() + std::ptrdiff_t(ringEnd), nb.end());
    ringStart = ringEnd;
  }
  nb.erase(nb.begin());
  return nb;
}

// GradientMethod::QuadraticFit (and MinimumCurvature's start and fallback): the gradient of a weighted
// least-squares quadratic over the ring neighbourhood in the frame (e1, e2, f), or of a plane where the
// quadratic is rank-deficient (linear set); false if neither fits
bool quadraticFitGradient(const VertexNormalInput& in, int v, const Vec3& f, const Vec3& e1, const Vec3& e2, Vec2& g,
                          bool& linear) {
  const TriMesh& mesh = in.mesh;
  const std::vector<int> nb = ringNeighbourhood(in, v);
  const Vec3& p = mesh.V[v];
  // 1-ring mean distance as the length scale
  double r1 = 0;
  int c1 = 0;
  for (int q = in.topo.vfStart[v]; q < in.topo.vfStart[v + 1]; ++q)
    for (int k = 0; k < 3; ++k)
      if (mesh.F[in.topo.vf[q]][k] != v) { r1 += (mesh.V[mesh.F[in.topo.vf[q]][k]] - p).norm(); ++c1; }
  r1 = c1 ? r1 / c1 : 1.0;
  if (!(r1 > 0 && nb.size() >= 2)) return false;
  const int n = int(nb.size());
  Eigen::MatrixXd A(n, 5);
  Eigen::VectorXd z(n);
  for (int i = 0; i < n; ++i) {
    const Vec3 d = mesh.V[nb[i]] - p;
    const double x = d.dot(e1) / r1, y = d.dot(e2) / r1, h = d.dot(f) / r1;
    // nearer points count much more (inverse 4th power of the distance, tuned on Franke's sets)
    const double q = 0.01 + x * x + y * y;
    const double w = 1.0 / (q * q);
    A.row(i) << w * x, w * y, w * x * x, w * x * y, w * y * y;
    z(i) = w * h;
  }
  bool ok = false;
  if (n >= 6) {
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    qr.setThreshold(1e-8);
    if (qr.rank() == 5) {
      const Eigen::VectorXd c = qr.solve(z);
      g = Vec2(c(0), c(1));
      ok = g.allFinite();
    }
  }
  if (!ok) {
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A.leftCols(2));
    qr.setThreshold(1e-8);
    if (qr.rank() == 2) {
      const Eigen::VectorXd c = qr.solve(z);
      g = Vec2(c(0), c(1));
      ok = g.allFinite();
      linear = ok;
    }
  }
  return ok;
}

// thesis eqs. 3-1 (interior) and 3-2 (boundary): the inverse-area weighted facet gradients in the frame
// (e1, e2, f); also the fallback of the quadratic fit. False if no facet is usable
bool inverseAreaGradient(const VertexNormalInput& in, int v, const Vec3& f, const Vec3& e1, const Vec3& e2, Vec2& g) {
  const TriMesh& mesh = in.mesh;
  const Topology& topo = in.topo;
  Vec2 num(0, 0);
  double den = 0;
  for (int q = topo.vfStart[v]; q < topo.vfStart[v + 1]; ++q) {
    const int t = topo.vf[q];
    if (in.degen[t]) continue;
    const auto& F = mesh.F[t];
    Vec2 gi;
    double Ai;
    if (!facetGradient(mesh.V[F[0]], mesh.V[F[1]], mesh.V[F[2]], e1, e2, f, gi, Ai) || !(Ai > 0)) continue;
    const double li = 1.0 / Ai;
    Vec2 term = gi;
    if (topo.boundary[v]) {
      // t'_i: the face across the edge of t_i opposite to v
      const int l = F[0] == v ? 0 : (F[1] == v ? 1 : 2);
      const auto& E = topo.edges[topo.faceEdge[t][l]];
      const int tp = E.f1 < 0 ? -1 : (E.f0 / 3 == t ? E.f1 / 3 : E.f0 / 3);
      Vec2 gp;
      double Ap;
      if (tp >= 0 && !in.degen[tp]) {
        const auto& G = mesh.F[tp];
        if (facetGradient(mesh.V[G[0]], mesh.V[G[1]], mesh.V[G[2]], e1, e2, f, gp, Ap) && Ap > 0)
          term = ((2 * Ai + Ap) * gi - Ai * gp) / (Ai + Ap);
      }
    }
    num += li * term;
    den += li;
  }
  if (!(den > 0)) return false;
  g = num / den;
  return g.allFinite();
}

// the per-vertex normal counts of Stats
struct VertexCounts {
  std::size_t flat = 0, linear = 0, isolated = 0, boundary = 0;
};

// every vertex's unit normal: the given one, or the frame tilted by the estimated gradient (quadratic fit
// or inverse-area facet gradients; the frame itself if neither works); a vertex without a frame or a
// usable given normal is flat
VertexCounts estimateVertexNormals(const VertexNormalInput& in, const std::vector<Vec3>* given,
                                   std::vector<Vec3>& normals, std::vector<char>& flat) {
  const int nv = int(in.mesh.V.size());
  const Topology& topo = in.topo;
  std::size_t flatCount = 0, linCount = 0, isolated = 0, bnd = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : flatCount, linCount, isolated, bnd)
  for (int v = 0; v < nv; ++v) {
    if (topo.vfStart[v] == topo.vfStart[v + 1]) { ++isolated; continue; }
    if (topo.boundary[v]) ++bnd;
    Vec3 f, e1, e2;
    if (!vertexFrame(in, v, f, e1, e2)) { flat[v] = 1; ++flatCount; normals[v] = Vec3(0, 0, 0); continue; }
    if (given) {
      Vec3 n = (*given)[v];
      if (!(n.norm() > 0) || !n.allFinite()) { flat[v] = 1; ++flatCount; continue; }
      n.normalize();
      normals[v] = n;
      continue;
    }
    Vec2 g(0, 0);
    bool ok = false;
    if (in.gradient != GradientMethod::InverseArea) {
      bool linear = false;
      ok = quadraticFitGradient(in, v, f, e1, e2, g, linear);
      if (linear) ++linCount;
    }
    if (!ok) ok = inverseAreaGradient(in, v, f, e1, e2, g);
    if (!ok) g = Vec2(0, 0);  // no usable facet: the frame plane itself
    Vec3 n = f - g.x() * e1 - g.y() * e2;
    normals[v] = n.normalized();
  }
  return {flatCount, linCount, isolated, bnd};
}

// GradientMethod::MinimumCurvature on a height field: the global estimate over the plane of (he1, he2),
// with the per-vertex normals as its start and fallback; false (normals unchanged) if the solve fails
bool globalGradientNormals(const VertexNormalInput& in, std::vector<Vec3>& normals) {
  const int nv = int(in.mesh.V.size());
  std::vector<Vec2> xy(nv), g(nv);
  std::vector<double> z(nv);
  for (int v = 0; v < nv; ++v) {
    const Vec3& p = in.mesh.V[v];
    xy[v] = Vec2(p.dot(in.he1), p.dot(in.he2));
    z[v] = p.dot(in.axis);
    const double c = normals[v].dot(in.axis);
    g[v] = std::abs(c) > 0 ? Vec2(-normals[v].dot(in.he1) / c, -normals[v].dot(in.he2) / c) : Vec2(0, 0);
  }
  if (!minimumCurvatureGradients(xy, z, in.topo.edges, g)) return false;
  for (int v = 0; v < nv; ++v)
    if (in.topo.vfStart[v] != in.topo.vfStart[v + 1])
      normals[v] = (in.axis - g[v].x() * in.he1 - g[v].y() * in.he2).normalized();
  return true;
}

// HeightField: every normal points along the axis (a reversed one is flipped); one orthogonal to it throws
void orientAlongAxis(const Topology& topo, const std::vector<char>& flat, const Vec3& axis, std::vector<Vec3>& normals) {
  for (int v = 0; v < int(normals.size()); ++v)
    if (!flat[v] && topo.vfStart[v] != topo.vfStart[v + 1] && !(normals[v].dot(axis) > 1e-6)) {
      if (normals[v].dot(axis) < -1e-6) { normals[v] = -normals[v]; continue; }
      throw InputError("vertex " + std::to_string(v) +
                       " has a normal orthogonal to the height-field axis; use the 3D (vertex normal) frame");
    }
}

// The control nets (eqs. 3-9..3-15): per face the 6 edge control points (the vertices' tangent planes) and
// the three b111 (one mean b111 for Blend::PlainCubic)
void controlNets(const TriMesh& mesh, const std::vector<Vec3>& normals, const std::vector<char>& flat, bool hf,
                 const Vec3& ax, Blend blend, std::vector<std::array<Vec3, 9>>& net) {
  const int nf = int(mesh.F.size());
  net.resize(nf);
  auto T = [&](int v, const Vec3& d) -> Vec3 {
    if (flat[v]) return d;
    const Vec3& n = normals[v];
    if (hf) return d - (n.dot(d) / n.dot(ax)) * ax;
    return d - n.dot(d) * n;
  };
#pragma omp parallel for schedule(static)
  for (int t = 0; t < nf; ++t) {
    const auto& F = mesh.F[t];
    Vec3 Vv[3], Vp[3];
    for (int k = 0; k < 3; ++k) {
      Vv[k] = mesh.V[F[k]];
      Vp[k] = hf ? Vec3(Vv[k] - Vv[k].dot(ax) * ax) : Vv[k];
    }
    // e[i][j]: edge control point next to vertex i towards vertex j (eq. 3-10 per coordinate)
    Vec3 e[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (i != j) e[i][j] = Vv[i] + T(F[i], Vv[j] - Vv[i]) / 3.0;
    auto& N = net[t];
    N[0] = e[0][1]; N[1] = e[0][2]; N[2] = e[1][0]; N[3] = e[1][2]; N[4] = e[2][0]; N[5] = e[2][1];
    // b111^a for the edge opposite vertex a (from b to c): the cross-boundary derivative along the
    // direction n_a = V_a - V_b - h_a (V_c - V_b) (orthogonal to the edge, eqs. 3-11/3-12) is
    //   D = 3 [ (1-t)^2 A + 2 t(1-t) M + t^2 C ],
    //   A = e[b][a] - V_b - h (e[b][c] - V_b), M = b111 - e[b][c] - h (e[c][b] - e[b][c]),
    //   C = e[c][a] - e[c][b] - h (V_c - e[c][b])        (eq. 3-13);
    // it is linear in t iff M = (A + C)/2 (eq. 3-14), hence b111^a below (eq. 3-15, re-derived).
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      const Vec3 ec = Vp[c] - Vp[b];
      const double l2 = ec.squaredNorm();
      double h = 0.5;
      if (l2 > 1e-24 * std::max(1.0, Vp[a].squaredNorm())) h = (Vp[a] - Vp[b]).dot(ec) / l2;
      if (!std::isfinite(h)) h = 0.5;
      const Vec3 A = e[b][a] - Vv[b] - h * (e[b][c] - Vv[b]);
      const Vec3 C = e[c][a] - e[c][b] - h * (Vv[c] - e[c][b]);
      N[6 + a] = e[b][c] + h * (e[c][b] - e[b][c]) + 0.5 * (A + C);
    }
    if (blend == Blend::PlainCubic) {
      const Vec3 m = (N[6] + N[7] + N[8]) / 3.0;
      N[6] = N[7] = N[8] = m;
    }
  }
}

}  // namespace

void C1Surface::build(std::vector<Vec3>* given) {
  topo_ = std::make_shared<const Topology>(checkedTopology(mesh_));
  const Topology& topo = *topo_;
  const int nv = int(mesh_.V.size()), nf = int(mesh_.F.size());
  const bool hf = opt_.frame == Frame::HeightField;
  if (hf) {
    if (!(opt_.axis.norm() > 0) || !opt_.axis.allFinite()) throw InputError("height-field axis must be a non-zero vector");
    opt_.axis.normalize();
  }
  stats_ = Stats();
  stats_.faces = std::size_t(nf);
  stats_.vertices = std::size_t(nv);

  std::vector<char> degen;
  const std::vector<Vec3> fn = faceNormals(mesh_, degen, stats_.degenerateFaces);
  if (hf) requireHeightField(fn, degen, opt_.axis);

  // vertex normals
  normals_.assign(nv, hf ? opt_.axis : Vec3(0, 0, 1));
  flat_.assign(nv, 0);
  VertexNormalInput in{mesh_, topo, fn, degen, opt_.gradient, hf, opt_.axis, Vec3(), Vec3()};
  std::tie(in.he1, in.he2) = completeFrame(hf ? opt_.axis : Vec3(0, 0, 1));
  const VertexCounts counts = estimateVertexNormals(in, given, normals_, flat_);
  if (hf && !given && opt_.gradient == GradientMethod::MinimumCurvature && nv > 0)
    stats_.globalGradients = globalGradientNormals(in, normals_);
  stats_.flatVertices = counts.flat;
  stats_.linearFitVertices = counts.linear;
  stats_.isolatedVertices = counts.isolated;
  stats_.boundaryVertices = counts.boundary;
  if (hf) orientAlongAxis(topo, flat_, opt_.axis, normals_);

  controlNets(mesh_, normals_, flat_, hf, opt_.axis, opt_.blend, net_);
}

std::vector<Vec2> C1Surface::heightGradients() const {
  std::vector<Vec2> g(normals_.size(), Vec2(0, 0));
  const auto [e1, e2] = frameAxes();
  for (std::size_t i = 0; i < normals_.size(); ++i) {
    const Vec3& n = normals_[i];
    const double c = n.dot(opt_.axis);
    if (std::abs(c) > 0) g[i] = Vec2(-n.dot(e1) / c, -n.dot(e2) / c);
  }
  return g;
}

std::array<Vec3, 12> C1Surface::controlNet(int face) const {
  const auto& F = mesh_.F[face];
  const auto& N = net_[face];
  return {mesh_.V[F[0]], N[0], N[1], N[2], N[4], mesh_.V[F[1]], N[3], N[5], mesh_.V[F[2]], N[6], N[7], N[8]};
}

template <class TT>
void C1Surface::evalImpl(int face, const TT& s, const TT& t, Vec3& P, Vec3& Ps, Vec3& Pt) const {
  const auto& F = mesh_.F[face];
  const auto& N = net_[face];
  const J u = J(1.0) - s - t, v = s, w = t;
  const J uu = u * u, vv = v * v, ww = w * w;
  J B[12];
  B[0] = uu * u;            // V0
  B[1] = 3.0 * (uu * v);    // e01
  B[2] = 3.0 * (uu * w);    // e02
  B[3] = 3.0 * (u * vv);    // e10
  B[4] = 3.0 * (vv * w);    // e12
  B[5] = 3.0 * (u * ww);    // e20
  B[6] = 3.0 * (v * ww);    // e21
  B[7] = vv * v;            // V1
  B[8] = ww * w;            // V2
  const J uvw6 = 6.0 * (u * v * w);
  const J w0 = vv * ww, w1 = ww * uu, w2 = uu * vv;  // eq. 3-16 weights of b111^0, ^1, ^2
  const J den = w0 + w1 + w2;
  if (den.v > 1e-300) {
    B[9] = uvw6 * (w0 / den);
    B[10] = uvw6 * (w1 / den);
    B[11] = uvw6 * (w2 / den);
  } else {  // at a corner: 6uvw and its gradient vanish
    B[9] = B[10] = B[11] = J(0.0);
  }
  const Vec3* cp[12] = {&mesh_.V[F[0]], &N[0], &N[1], &N[2], &N[3], &N[4], &N[5],
                        &mesh_.V[F[1]], &mesh_.V[F[2]], &N[6], &N[7], &N[8]};
  // plain scalar sums in control-point order (no Eigen temporaries in the loop)
  double p[3] = {0, 0, 0}, ps[3] = {0, 0, 0}, pt[3] = {0, 0, 0};
  for (int k = 0; k < 12; ++k) {
    const double* c = cp[k]->data();
    for (int i = 0; i < 3; ++i) {
      p[i] += B[k].v * c[i];
      ps[i] += B[k].s * c[i];
      pt[i] += B[k].t * c[i];
    }
  }
  P = Vec3(p[0], p[1], p[2]);
  Ps = Vec3(ps[0], ps[1], ps[2]);
  Pt = Vec3(pt[0], pt[1], pt[2]);
}

std::vector<C1Surface::EdgeFaces> C1Surface::edges() const {
  std::vector<EdgeFaces> out;
  out.reserve(topo_->edges.size());
  for (const auto& e : topo_->edges) out.push_back({e.a, e.b, e.f0 / 3, e.f1 < 0 ? -1 : e.f1 / 3});
  return out;
}

std::vector<std::array<int, 3>> C1Surface::faceNeighbours() const {
  std::vector<std::array<int, 3>> nb(mesh_.F.size(), {-1, -1, -1});
  for (const auto& e : topo_->edges)
    if (e.f1 >= 0) {
      nb[std::size_t(e.f0 / 3)][std::size_t(e.f0 % 3)] = e.f1 / 3;
      nb[std::size_t(e.f1 / 3)][std::size_t(e.f1 % 3)] = e.f0 / 3;
    }
  return nb;
}

PatchJet C1Surface::jet(int face, const Vec3& bary) const {
  const double sum = bary.sum();
  const Vec3 b = std::abs(sum) > 0 ? Vec3(bary / sum) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
  PatchJet j;
  evalImpl(face, J(b.y(), 1, 0), J(b.z(), 0, 1), j.P, j.Ps, j.Pt);
  return j;
}

Vec3 C1Surface::eval(int face, const Vec3& bary) const { return jet(face, bary).P; }

SurfacePoint C1Surface::at(int face, const Vec3& bary) const {
  const double sum = bary.sum();
  SurfacePoint sp;
  sp.face = face;
  sp.bary = std::abs(sum) > 0 ? Vec3(bary / sum) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
  const PatchJet j = jet(face, sp.bary);
  sp.point = j.P;
  sp.normal = j.normal();
  if (sp.normal.squaredNorm() == 0) {  // degenerate parametrization there: use the flat face normal
    const auto& F = mesh_.F[face];
    const Vec3 n = (mesh_.V[F[1]] - mesh_.V[F[0]]).cross(mesh_.V[F[2]] - mesh_.V[F[0]]);
    sp.normal = n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 0);
  }
  return sp;
}

// ------------------------------------------------------------------------------------------------
// refinement

namespace {

/// Where refine() puts its vertices: the referenced input vertices in their order (vmap: input -> output,
/// -1 if unreferenced), then k - 1 per edge, then the interior grid points of each face.
struct RefineLayout {
  int k = 1;
  double ik = 1;  ///< 1 / k
  std::vector<int> vmap;
  int edgeBase = 0, perEdge = 0, faceBase = 0, perFace = 0, total = 0;
};

RefineLayout refineLayout(const Topology& topo, int nv, int nf, int k) {
  RefineLayout L;
  L.k = k;
  L.vmap.assign(std::size_t(nv), -1);
  int n = 0;
  for (int v = 0; v < nv; ++v)
    if (topo.vfStart[v] != topo.vfStart[v + 1]) L.vmap[v] = n++;
  L.edgeBase = n;
  L.perEdge = k - 1;
  L.perFace = (k - 1) * (k - 2) / 2;
  L.faceBase = L.edgeBase + int(topo.edges.size()) * L.perEdge;
  L.total = L.faceBase + nf * L.perFace;
  L.ik = 1.0 / k;
  return L;
}

/// the local index (0, 1, 2) of vertex v in face F
int corner(const std::array<int, 3>& F, int v) { return F[0] == v ? 0 : (F[1] == v ? 1 : 2); }

/// an output vertex's normal at an input vertex: the mean of the patch normals at its corners (the patch
/// normal at the corner of its first face if they cancel)
void cornerNormals(const C1Surface& S, const RefineLayout& L, std::vector<Vec3>& nrm) {
  const TriMesh& mesh = S.mesh();
  const Topology& topo = S.topology();
  const int nv = int(mesh.V.size());
  for (int v = 0; v < nv; ++v) {
    if (L.vmap[v] < 0) continue;
    const int f = topo.vf[topo.vfStart[v]];
    Vec3 b(0, 0, 0);
    b[corner(mesh.F[f], v)] = 1;
    Vec3 acc(0, 0, 0);
    for (int q = topo.vfStart[v]; q < topo.vfStart[v + 1]; ++q) {
      const int g = topo.vf[q];
      Vec3 bb(0, 0, 0);
      bb[corner(mesh.F[g], v)] = 1;
      acc += S.at(g, bb).normal;
    }
    nrm[L.vmap[v]] = acc.norm() > 0 ? Vec3(acc.normalized()) : S.at(f, b).normal;
  }
}

/// the k - 1 vertices of every edge, from the edge's first face (points of the shared edge curve); with
/// nrm, their normals: the mean of the two faces' patch normals there
void edgeVertices(const C1Surface& S, const RefineLayout& L, std::vector<Vec3>& V, std::vector<Vec3>* nrm) {
  const TriMesh& mesh = S.mesh();
  const Topology& topo = S.topology();
  const int ne = int(topo.edges.size()), k = L.k;
  const double ik = L.ik;
#pragma omp parallel for schedule(static)
  for (int e = 0; e < ne; ++e) {
    const auto& E = topo.edges[e];
    const int f = E.f0 / 3;
    const auto& F = mesh.F[f];
    const int ia = corner(F, E.a);
    const int ib = corner(F, E.b);
    for (int m = 1; m < k; ++m) {
      Vec3 b(0, 0, 0);
      b[ia] = 1.0 - m * ik;
      b[ib] = m * ik;
      const int id = L.edgeBase + e * L.perEdge + (m - 1);
      if (nrm) {
        SurfacePoint sp = S.at(f, b);
        V[id] = sp.point;
        Vec3 nn = sp.normal;
        if (E.f1 >= 0) {
          const int g = E.f1 / 3;
          const auto& G = mesh.F[g];
          Vec3 bg(0, 0, 0);
          bg[corner(G, E.a)] = 1.0 - m * ik;
          bg[corner(G, E.b)] = m * ik;
          nn += S.at(g, bg).normal;
        }
        (*nrm)[id] = nn.norm() > 0 ? Vec3(nn.normalized()) : sp.normal;
      } else {
        V[id] = S.eval(f, b);
      }
    }
  }
}

/// The output vertex of face f's grid point (i, j), i + j <= k (barycentric (k-i-j, i, j)/k): a corner's
/// vertex, an edge's (shared with the neighbour), or the face's own interior point.
class FaceGrid {
 public:
  FaceGrid(const Topology& topo, const RefineLayout& L, const std::array<int, 3>& F, int f)
      : topo_(topo), L_(L), F_(F), f_(f) {}
  int operator()(int i, int j) const {
    const int k = L_.k, c = k - i - j;
    if (i == 0 && j == 0) return L_.vmap[F_[0]];
    if (i == k) return L_.vmap[F_[1]];
    if (j == k) return L_.vmap[F_[2]];
    if (j == 0) return edgePoint(0, 1, i);
    if (i == 0) return edgePoint(0, 2, j);
    if (c == 0) return edgePoint(1, 2, j);
    // interior: row-major over j = 1..k-2, i = 1..k-1-j
    int idx = 0;
    for (int jj = 1; jj < j; ++jj) idx += k - 1 - jj;
    idx += i - 1;
    return L_.faceBase + f_ * L_.perFace + idx;
  }

 private:
  /// the vertex m steps from local corner la to lb
  int edgePoint(int la, int lb, int m) const {
    const int l = 3 - la - lb;  // local edge opposite l
    const int e = topo_.faceEdge[f_][l];
    if (e < 0) return L_.vmap[F_[la]];  // repeated vertex: collapsed edge
    const auto& E = topo_.edges[e];
    const int mm = E.a == F_[la] ? m : L_.k - m;
    return L_.edgeBase + e * L_.perEdge + (mm - 1);
  }
  const Topology& topo_;
  const RefineLayout& L_;
  const std::array<int, 3>& F_;
  int f_;
};

/// every face's interior vertices (with nrm, their patch normals) and its k x k triangles
void faceGrids(const C1Surface& S, const RefineLayout& L, TriMesh& out, std::vector<Vec3>* nrm) {
  const TriMesh& mesh = S.mesh();
  const int nf = int(mesh.F.size()), k = L.k;
  const double ik = L.ik;
  out.F.resize(std::size_t(nf) * k * k);
#pragma omp parallel for schedule(static)
  for (int f = 0; f < nf; ++f) {
    const FaceGrid id(S.topology(), L, mesh.F[f], f);
    for (int j = 1; j < k - 1; ++j)
      for (int i = 1; i < k - j; ++i) {
        const int vid = id(i, j);
        const Vec3 b((k - i - j) * ik, i * ik, j * ik);
        if (nrm) {
          const SurfacePoint sp = S.at(f, b);
          out.V[vid] = sp.point;
          (*nrm)[vid] = sp.normal;
        } else {
          out.V[vid] = S.eval(f, b);
        }
      }
    std::size_t o = std::size_t(f) * k * k;
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k - j; ++i) {
        out.F[o++] = {id(i, j), id(i + 1, j), id(i, j + 1)};
        if (i + j < k - 1) out.F[o++] = {id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      }
  }
}

}  // namespace

TriMesh C1Surface::refine(int k, std::vector<Vec3>* outNormals) const {
  if (!kSubdivisionsRange.contains(k)) throw InputError("refinement: k must be an integer in " + kSubdivisionsRange.text(true));
  const int nv = int(mesh_.V.size()), nf = int(mesh_.F.size());
  const RefineLayout L = refineLayout(*topo_, nv, nf, k);
  TriMesh out;
  out.V.resize(L.total);
  std::vector<Vec3> nrm(outNormals ? L.total : 0);
  for (int v = 0; v < nv; ++v)
    if (L.vmap[v] >= 0) out.V[L.vmap[v]] = mesh_.V[v];
  if (outNormals) cornerNormals(*this, L, nrm);
  edgeVertices(*this, L, out.V, outNormals ? &nrm : nullptr);
  faceGrids(*this, L, out, outNormals ? &nrm : nullptr);
  if (outNormals) *outNormals = std::move(nrm);
  return out;
}

double enclosedVolume(const TriMesh& m) {
  double v = 0;
  for (const auto& f : m.F) v += m.V[f[0]].dot(m.V[f[1]].cross(m.V[f[2]]));
  return v / 6.0;
}

// ------------------------------------------------------------------------------------------------
// planar scalar fields

namespace {
TriMesh planarMesh(const std::vector<Vec2>& xy, const std::vector<double>& f, const std::vector<std::array<int, 3>>& tris) {
  if (xy.size() != f.size()) throw InputError("one value per point is needed");
  TriMesh m;
  m.V.resize(xy.size());
  for (std::size_t i = 0; i < xy.size(); ++i) m.V[i] = Vec3(xy[i].x(), xy[i].y(), f[i]);
  m.F = tris;
  for (auto& t : m.F) {  // counter-clockwise in the plane
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= int(xy.size())) throw TopologyError("triangle uses a point index out of range");
    const Vec2 a = xy[t[0]], b = xy[t[1]], c = xy[t[2]];
    if ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x() < 0) std::swap(t[1], t[2]);
  }
  return m;
}
Options hfOptions(GradientMethod g, Blend b) {
  Options o;
  o.gradient = g;
  o.frame = Frame::HeightField;
  o.axis = Vec3(0, 0, 1);
  o.blend = b;
  return o;
}
}  // namespace

std::vector<Vec2> estimateGradients2D(const std::vector<Vec2>& xy, const std::vector<double>& f,
                                      const std::vector<std::array<int, 3>>& tris, GradientMethod method) {
  const C1Surface s(planarMesh(xy, f, tris), hfOptions(method, Blend::GoodmanSaid));
  auto g = s.heightGradients();
  const auto [e1, e2] = s.frameAxes();
  // back to (x, y): the frame of the z axis is (e1, e2) = rotation of (x, y)
  std::vector<Vec2> out(g.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    const Vec3 G = g[i].x() * e1 + g[i].y() * e2;
    out[i] = Vec2(G.x(), G.y());
  }
  return out;
}

namespace {
C1Surface makeHeight(const std::vector<Vec2>& xy, const std::vector<double>& f, const std::vector<std::array<int, 3>>& tris,
                     GradientMethod method, const std::vector<Vec2>& grads, Blend blend) {
  TriMesh m = planarMesh(xy, f, tris);
  const Options o = hfOptions(method, blend);
  if (grads.empty()) return C1Surface(std::move(m), o);
  if (grads.size() != xy.size()) throw InputError("one gradient per point is needed");
  std::vector<Vec3> n(grads.size());
  for (std::size_t i = 0; i < grads.size(); ++i) n[i] = Vec3(-grads[i].x(), -grads[i].y(), 1.0).normalized();
  return C1Surface(std::move(m), std::move(n), o);
}
}  // namespace

HeightInterpolant::HeightInterpolant(const std::vector<Vec2>& xy, const std::vector<double>& f,
                                     const std::vector<std::array<int, 3>>& tris, GradientMethod method,
                                     std::vector<Vec2> gradients, Blend blend)
    : xy_(xy), surf_(makeHeight(xy, f, tris, method, gradients, blend)) {
  if (gradients.empty()) {
    grads_.resize(xy.size());
    const auto g = surf_.heightGradients();
    const auto [e1, e2] = surf_.frameAxes();
    for (std::size_t i = 0; i < g.size(); ++i) {
      const Vec3 G = g[i].x() * e1 + g[i].y() * e2;
      grads_[i] = Vec2(G.x(), G.y());
    }
  } else {
    grads_ = std::move(gradients);
  }
}

double HeightInterpolant::value(int tri, const Vec2& p) const { return value(tri, p, nullptr); }

double HeightInterpolant::value(int tri, const Vec2& p, Vec2* grad) const {
  const auto& F = surf_.mesh().F[tri];  // reoriented CCW, same vertex set
  const Vec2 a = xy_[F[0]], b = xy_[F[1]], c = xy_[F[2]];
  const double det = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  const Vec2 d = p - a;
  const double s = (d.x() * (c - a).y() - d.y() * (c - a).x()) / det;
  const double t = ((b - a).x() * d.y() - (b - a).y() * d.x()) / det;
  const PatchJet j = surf_.jet(tri, Vec3(1 - s - t, s, t));
  if (grad) {
    // P(s,t) = (x, y, z): dz/dx, dz/dy from the 2x2 Jacobian of (x, y) wrt (s, t)
    Eigen::Matrix2d Jm;
    Jm << j.Ps.x(), j.Pt.x(), j.Ps.y(), j.Pt.y();
    const Eigen::RowVector2d dz(j.Ps.z(), j.Pt.z());
    const Eigen::RowVector2d gz = dz * Jm.inverse();
    *grad = Vec2(gz(0), gz(1));
  }
  return j.P.z();
}

}  // namespace pectus::c1
