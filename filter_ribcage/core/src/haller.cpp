#include "pectus/ribcage/haller.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pectus::ribcage {

namespace {
using Vec3 = Eigen::Vector3d;
struct Tri { Vec3 a, b, c; };

// intersections of the axis-parallel line {coordinate `axis` free, the other two fixed at (u, v)}
// with triangle t; returns the free coordinate
bool lineHit(const Tri& t, int axis, double u, double v, double& out) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const double ax = t.a[i] - u, ay = t.a[j] - v, bx = t.b[i] - u, by = t.b[j] - v, cx = t.c[i] - u, cy = t.c[j] - v;
  const double w0 = bx * cy - by * cx, w1 = cx * ay - cy * ax, w2 = ax * by - ay * bx;
  const bool pos = w0 >= 0 && w1 >= 0 && w2 >= 0, neg = w0 <= 0 && w1 <= 0 && w2 <= 0;
  const double s = w0 + w1 + w2;
  if (!(pos || neg) || s == 0) return false;
  out = (w0 * t.a[axis] + w1 * t.b[axis] + w2 * t.c[axis]) / s;
  return true;
}

constexpr int kLateralCandidates = 32;  ///< vertices tried per side, most lateral first

/// the `n` vertices with the largest sg * x, largest first (of equal ones, the first in the mesh first)
std::vector<Vec3> lateralMost(const CMeshO& m, double sg, int n) {
  std::vector<Vec3> v;
  for (const auto& p : m.vert)
    if (!p.IsD()) v.push_back(toEigen(p.cP()));
  const auto k = std::min<std::ptrdiff_t>(n, std::ptrdiff_t(v.size()));
  std::stable_sort(v.begin(), v.end(), [sg](const Vec3& a, const Vec3& b) { return sg * a.x() > sg * b.x(); });
  v.resize(std::size_t(k));
  return v;
}

/// the inner surface's x on the side sg (-1 right, +1 left) along the ray {y, z fixed}: the second hit from
/// outside among the hits on that side, or none when the ray crosses that side fewer than twice
std::optional<double> innerWall(const std::vector<Tri>& tris, double sg, double y, double z) {
  std::vector<double> side;
  for (const auto& t : tris) {
    double x;
    if (lineHit(t, 0, y, z, x) && sg * x > 0) side.push_back(sg * x);
  }
  if (side.size() < 2) return std::nullopt;
  std::partial_sort(side.begin(), side.begin() + 2, side.end(), std::greater<double>());
  return sg * side[1];
}
}  // namespace

std::optional<HallerMeasure> measureHaller(const CMeshO& m) {
  std::vector<Tri> tris;
  for (const auto& f : m.face)
    if (!f.IsD()) tris.push_back({toEigen(f.cP(0)), toEigen(f.cP(1)), toEigen(f.cP(2))});
  if (tris.empty()) return std::nullopt;
  HallerMeasure r;
  // transverse: per side, a ray along x through the lateral-most vertex (slightly off it) crosses the bone's
  // outer and inner surface; the second hit on that side is the inner one. A vertex whose ray does not cross
  // its side's bone twice (the tip of a sliver face, a corner the ray grazes) gives way to the next most
  // lateral vertex.
  double xin[2];
  for (int si = 0; si < 2; ++si) {
    const double sg = si == 0 ? -1 : 1;
    std::optional<double> inner;
    for (const Vec3& ext : lateralMost(m, sg, kLateralCandidates)) {
      inner = innerWall(tris, sg, ext.y() + 0.011, ext.z() + 0.013);
      if (inner) break;
    }
    if (!inner) return std::nullopt;
    xin[si] = *inner;
  }
  r.xInnerRight = xin[0];
  r.xInnerLeft = xin[1];
  r.transverse = xin[1] - xin[0];
  // AP: rays along +y from y = 0 at |x| <= 2 mm, every 0.5 mm in z
  std::vector<Tri> mid;
  double zlo = std::numeric_limits<double>::max(), zhi = -zlo;
  for (const auto& t : tris) {
    const double x0 = std::min({t.a.x(), t.b.x(), t.c.x()}), x1 = std::max({t.a.x(), t.b.x(), t.c.x()});
    const double y1 = std::max({t.a.y(), t.b.y(), t.c.y()});
    if (x1 < -2.5 || x0 > 2.5 || y1 <= 0) continue;
    mid.push_back(t);
    zlo = std::min({zlo, t.a.z(), t.b.z(), t.c.z()});
    zhi = std::max({zhi, t.a.z(), t.b.z(), t.c.z()});
  }
  r.ap = std::numeric_limits<double>::max();
  for (double z = std::floor(zlo * 2) / 2; z <= zhi; z += 0.5)
    for (int xi = -2; xi <= 2; ++xi) {
      double first = std::numeric_limits<double>::max();
      for (const auto& t : mid) {
        double y;
        if (lineHit(t, 1, z, double(xi) + 1e-4, y) && y > 0) first = std::min(first, y);
      }
      if (first < r.ap) { r.ap = first; r.zAp = z; }
    }
  if (!(r.ap < 1e30)) return std::nullopt;
  r.index = r.transverse / r.ap;
  return r;
}

}  // namespace pectus::ribcage
