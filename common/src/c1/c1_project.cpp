// Closest-point projection onto the C1 surface: a uniform grid over the patches' bounding boxes (a patch
// lies in the convex hull of its control net, eq. 3-16 blends the three b111 convexly), visited in shells
// of growing radius around the query (branch and bound on the box distance), and a projected
// Gauss-Newton minimization of |S(s,t) - p|^2 over each candidate triangle.
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "c1_internal.h"
#include "pectus/c1/surface.h"
#include "pectus/errors.h"
#include "pectus/grid_cell.h"

namespace pectus::c1 {

namespace {
std::mutex gIndexMutex;

void clampST(double& s, double& t) {
  if (!std::isfinite(s)) s = 1.0 / 3;
  if (!std::isfinite(t)) t = 1.0 / 3;
  s = std::max(s, 0.0);
  t = std::max(t, 0.0);
  if (s + t > 1) {
    const double d = 0.5 * (s + t - 1);
    s -= d;
    t -= d;
    s = std::clamp(s, 0.0, 1.0);
    t = std::clamp(t, 0.0, 1.0);
    if (s + t > 1) t = 1 - s;
  }
}

/// squared distance from p to the box [a, b], of the distances scaled by `scale`
double boxDist2(const Vec3& p, const Vec3& a, const Vec3& b, double scale) {
  double d = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = scale * (p[k] < a[k] ? a[k] - p[k] : (p[k] > b[k] ? p[k] - b[k] : 0.0));
    d += e * e;
  }
  return d;
}

/// 1, or for a query so far from the surface that squared distances would overflow a double (beyond
/// ~1e154; e.g. 1e300) the power of two that brings its offset to about 1: every squared distance the
/// search compares is of the distances times this factor (exact, so the order is kept)
double distanceScale(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const double far = std::max((p - lo).cwiseAbs().maxCoeff(), (p - hi).cwiseAbs().maxCoeff());
  return far > 1e100 ? std::ldexp(1.0, -std::ilogb(far)) : 1.0;
}

/// The faces a query has tried, per thread: a face's stamp equals the query's counter once tried. The stamps
/// are cleared when the thread queries another surface, or when the counter wraps.
struct FaceStamps {
  std::vector<unsigned> stamp;
  unsigned counter = 0;
  const void* owner = nullptr;
  /// starts a query on a surface of nf faces
  void next(const void* surface, int nf) {
    if (owner != surface || stamp.size() != std::size_t(nf)) {
      stamp.assign(nf, 0);
      counter = 0;
      owner = surface;
    }
    if (++counter == 0) { std::fill(stamp.begin(), stamp.end(), 0); counter = 1; }
  }
  /// face f not tried yet in this query (it is marked tried)
  bool first(int f) {
    if (stamp[f] == counter) return false;
    stamp[f] = counter;
    return true;
  }
};

/// the start of the search on face f: (s, t) of p's projection onto the flat triangle (its centroid if the
/// triangle is degenerate), clamped into it
void flatStart(const TriMesh& mesh, int f, const Vec3& p, double& s, double& t) {
  const auto& F = mesh.F[f];
  const Vec3 a = mesh.V[F[0]], e1 = mesh.V[F[1]] - a, e2 = mesh.V[F[2]] - a, d = p - a;
  s = 1.0 / 3;
  t = 1.0 / 3;
  const double m11 = e1.dot(e1), m12 = e1.dot(e2), m22 = e2.dot(e2), det = m11 * m22 - m12 * m12;
  if (det > 1e-14 * m11 * m22) {
    s = (m22 * e1.dot(d) - m12 * e2.dot(d)) / det;
    t = (m11 * e2.dot(d) - m12 * e1.dot(d)) / det;
  }
  clampST(s, t);
}

/// Newton's matrix: the Gauss-Newton matrix H plus the scaled residual r times the patch's second
/// derivatives at (s, t), by central differences of the first ones (Gauss-Newton alone converges slowly
/// when the residual is large against the radius of curvature)
Eigen::Matrix2d withCurvature(const C1Surface& S, int f, double s, double t, const Vec3& r, const Eigen::Matrix2d& H) {
  Eigen::Matrix2d Hn = H;
  const double h = 1e-5;
  auto jj = [&](double ds, double dt) { return S.jet(f, Vec3(1 - s - ds - t - dt, s + ds, t + dt)); };
  const PatchJet sp = jj(h, 0), sm = jj(-h, 0), tp = jj(0, h), tm = jj(0, -h);
  const Vec3 Pss = (sp.Ps - sm.Ps) / (2 * h), Ptt = (tp.Pt - tm.Pt) / (2 * h), Pst = (tp.Ps - tm.Ps) / (2 * h);
  Hn(0, 0) += r.dot(Pss);
  Hn(1, 1) += r.dot(Ptt);
  Hn(0, 1) += r.dot(Pst);
  Hn(1, 0) += r.dot(Pst);
  return Hn;
}

/// One projected Newton step on patch f from (s, t) (jet j, scaled squared distance fv to p), halved until it
/// gains; (s, t), j and fv move there. False if no step gains or the move is negligible.
bool newtonStep(const C1Surface& S, int f, const Vec3& p, double sc, double& s, double& t, PatchJet& j, double& fv) {
  // the residual scaled by sc, so the whole Newton system (J^T J + r.P'') d = -J^T r is scaled by sc
  const Vec3 r = sc * (j.P - p);
  Eigen::Matrix2d H;
  H << j.Ps.dot(j.Ps), j.Ps.dot(j.Pt), j.Ps.dot(j.Pt), j.Pt.dot(j.Pt);
  H *= sc;
  const Vec2 g(j.Ps.dot(r), j.Pt.dot(r));
  H += 1e-12 * (H.trace() + 1e-300) * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d Hn = withCurvature(S, f, s, t, r, H);
  const bool pd = Hn(0, 0) > 0 && Hn.determinant() > 1e-12 * H.determinant();
  Vec2 step = pd ? Vec2(-Hn.ldlt().solve(g)) : Vec2(-H.ldlt().solve(g));
  if (!step.allFinite()) step = -g;
  for (int ls = 0; ls < 12; ++ls) {
    double s2 = s + step.x(), t2 = t + step.y();
    clampST(s2, t2);
    const PatchJet j2 = S.jet(f, Vec3(1 - s2 - t2, s2, t2));
    const double f2 = (sc * (j2.P - p)).squaredNorm();
    if (f2 < fv) {
      const double ds = std::abs(s2 - s) + std::abs(t2 - t);
      s = s2; t = t2; j = j2; fv = f2;
      return ds > 1e-13;
    }
    step *= 0.5;
  }
  return false;
}

/// the closest point of patch f to p by projected Newton from the flat projection: its (s, t), and the
/// squared distance scaled by sc
double projectOntoPatch(const C1Surface& S, int f, const Vec3& p, double sc, double& s, double& t) {
  flatStart(S.mesh(), f, p, s, t);
  PatchJet j = S.jet(f, Vec3(1 - s - t, s, t));
  double fv = (sc * (j.P - p)).squaredNorm();
  for (int it = 0; it < 30; ++it)
    if (!newtonStep(S, f, p, sc, s, t, j, fv)) break;
  return fv;
}

/// A lower bound of the distance from p to any grid cell outside the box of cells [lo, hi] (grid origin o,
/// cell size cs, dim cells per axis); all: the box holds every cell.
double outsideBound(const Vec3& p, const Vec3& o, double cs, const int dim[3], const int lo[3], const int hi[3],
                    bool& all) {
  double bound = std::numeric_limits<double>::max();
  all = true;
  for (int k = 0; k < 3; ++k) {
    if (lo[k] > 0) { all = false; bound = std::min(bound, p[k] - (o[k] + lo[k] * cs)); }
    if (hi[k] < dim[k] - 1) { all = false; bound = std::min(bound, o[k] + (hi[k] + 1) * cs - p[k]); }
  }
  return bound;
}
}  // namespace

void C1Surface::buildIndex() const {
  std::lock_guard<std::mutex> lock(gIndexMutex);
  if (index_) return;
  auto ix = std::make_unique<Index>();
  const int nf = int(mesh_.F.size());
  if (nf == 0) throw TopologyError("closest point: the surface has no faces");
  ix->bmin.resize(nf);
  ix->bmax.resize(nf);
  ix->lo = Vec3::Constant(std::numeric_limits<double>::max());
  ix->hi = -ix->lo;
  double ext = 0;
  for (int f = 0; f < nf; ++f) {
    const auto cn = controlNet(f);
    Vec3 a = cn[0], b = cn[0];
    for (const auto& q : cn) { a = a.cwiseMin(q); b = b.cwiseMax(q); }
    ix->bmin[f] = a;
    ix->bmax[f] = b;
    ix->lo = ix->lo.cwiseMin(a);
    ix->hi = ix->hi.cwiseMax(b);
    ext += (b - a).maxCoeff();
  }
  const Vec3 size = ix->hi - ix->lo;
  double cs = std::max(1.5 * ext / nf, 1e-9 * std::max(1.0, size.maxCoeff()));
  auto cells = [&](double c) {
    double n = 1;
    for (int k = 0; k < 3; ++k) n *= std::floor(size[k] / c) + 1;
    return n;
  };
  while (cells(cs) > 4.0 * nf + 64) cs *= 1.25;
  ix->cs = cs;
  for (int k = 0; k < 3; ++k) ix->dim[k] = int(std::floor(size[k] / cs)) + 1;
  const int ncell = ix->dim[0] * ix->dim[1] * ix->dim[2];
  auto range = [&](int f, int lo[3], int hi[3]) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = clampedCell((ix->bmin[f][k] - ix->lo[k]) / cs, ix->dim[k]);
      hi[k] = clampedCell((ix->bmax[f][k] - ix->lo[k]) / cs, ix->dim[k]);
    }
  };
  ix->cellStart.assign(ncell + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int> fill;
    if (pass == 1) {
      for (int c = 0; c < ncell; ++c) ix->cellStart[c + 1] += ix->cellStart[c];
      ix->cellFaces.resize(ix->cellStart[ncell]);
      fill.assign(ix->cellStart.begin(), ix->cellStart.end() - 1);
    }
    for (int f = 0; f < nf; ++f) {
      int lo[3], hi[3];
      range(f, lo, hi);
      for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int x = lo[0]; x <= hi[0]; ++x) {
            const int c = ix->cell(x, y, z);
            if (pass == 0) ++ix->cellStart[c + 1];
            else ix->cellFaces[fill[c]++] = f;
          }
    }
  }
  index_ = std::move(ix);
}

SurfacePoint C1Surface::closestPoint(const Vec3& p) const {
  if (!p.allFinite()) throw InputError("closest point: the query point has a NaN/Inf coordinate");
  if (!index_) buildIndex();
  const Index& ix = *index_;
  thread_local FaceStamps stamps;
  stamps.next(this, int(mesh_.F.size()));

  const double sc = distanceScale(p, ix.lo, ix.hi);
  double best = std::numeric_limits<double>::max();
  SurfacePoint res;
  // a face not tried yet whose box is nearer than the best point so far: its patch's closest point
  auto tryFace = [&](int f) {
    if (!stamps.first(f) || boxDist2(p, ix.bmin[f], ix.bmax[f], sc) >= best) return;
    double s, t;
    const double fv = projectOntoPatch(*this, f, p, sc, s, t);
    if (fv < best) {
      best = fv;
      res.face = f;
      res.bary = Vec3(1 - s - t, s, t);
    }
  };

  // the cells in shells of growing radius r around the query's cell, until the cells not visited yet are
  // all farther than the best point
  int c[3];
  for (int k = 0; k < 3; ++k) c[k] = clampedCell((p[k] - ix.lo[k]) / ix.cs, ix.dim[k]);
  const int maxR = std::max({ix.dim[0], ix.dim[1], ix.dim[2]});
  for (int r = 0; r <= maxR; ++r) {
    int lo[3], hi[3];
    for (int k = 0; k < 3; ++k) { lo[k] = c[k] - r; hi[k] = c[k] + r; }
    for (int z = std::max(lo[2], 0); z <= std::min(hi[2], ix.dim[2] - 1); ++z)
      for (int y = std::max(lo[1], 0); y <= std::min(hi[1], ix.dim[1] - 1); ++y)
        for (int x = std::max(lo[0], 0); x <= std::min(hi[0], ix.dim[0] - 1); ++x) {
          const bool shell = x == lo[0] || x == hi[0] || y == lo[1] || y == hi[1] || z == lo[2] || z == hi[2];
          if (!shell) continue;
          const int cc = ix.cell(x, y, z);
          for (int q = ix.cellStart[cc]; q < ix.cellStart[cc + 1]; ++q) tryFace(ix.cellFaces[q]);
        }
    bool all;
    const double bound = outsideBound(p, ix.lo, ix.cs, ix.dim, lo, hi, all);
    if (all) break;
    if (res.face >= 0 && bound > 0 && best <= (sc * bound) * (sc * bound)) break;
  }
  SurfacePoint out = at(res.face, res.bary);
  out.distance = (sc * (out.point - p)).norm() / sc;
  return out;
}

}  // namespace pectus::c1
