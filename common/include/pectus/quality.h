// Element shape quality measures of the thesis (chapter 4.2.2).
//  - triangle quality alpha, eq. 3-20
//  - Knupp's quadrilateral shape quality beta, eqs. 3-22/3-23, extended to non-planar surface quads
// All computations in double precision. Host-free (Eigen only).
#pragma once
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <vector>

namespace pectus {

using Vec3 = Eigen::Vector3d;

/// alpha = 2*sqrt(3) * |AB x AC| / (|AB|^2 + |BC|^2 + |CA|^2)   (eq. 3-20)
/// 1 for an equilateral triangle, 0 for a degenerate one (and for coincident points).
double triangleAlpha(const Vec3& a, const Vec3& b, const Vec3& c);

/// Signed alpha: the sign of (AB x AC) . n. Negative when the triangle is flipped against the
/// reference normal n (used to reject folding moves).
double triangleAlphaSigned(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n);

/// Knupp's shape quality of the quad p0 p1 p2 p3 (in boundary order).
///   beta = 8 / sum_k (|e1_k|^2 + |e2_k|^2) / a_k,   a_k = (e1_k x e2_k) . n
/// with e1_k = p_{k+1} - p_k, e2_k = p_{k+3} - p_k (indices mod 4), which is eq. 3-23 since
/// (1 + r^2)/(r sin theta) = (|e1|^2 + |e2|^2) / (|e1||e2| sin theta).
/// For a planar quad a_k is the signed parallelogram area at corner k (eq. 3-22). For a surface
/// (non-planar) quad n is the unit normal of the quad, the direction of the cross product of its
/// diagonals (p2 - p0) x (p3 - p1), so the metric is that of the quad seen along its own normal.
/// Returns 1 for a square, tends to 0 as an interior angle tends to 180 degrees, and 0 when any
/// corner has a_k <= 0 (a non-convex, degenerate or inverted quad), as Knupp defines it.
double quadBeta(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3);

/// Same with a given reference unit normal n (for example the surface normal): a quad whose
/// corners turn the other way round n is inverted and gets 0.
double quadBetaWithNormal(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, const Vec3& n);

/// A triangle's cross product AB x AC and edge sum |AB|^2 + |BC|^2 + |CA|^2, computed once for its alpha
/// and its signed alphas against several normals (the MGA fold test at every node of an element).
/// alpha() is triangleAlpha, alphaSigned(n) is triangleAlphaSigned, to the bit.
struct TriangleShape {
  Vec3 cross;
  double edgeSum;
  TriangleShape(const Vec3& a, const Vec3& b, const Vec3& c)
      : cross((b - a).cross(c - a)), edgeSum((b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm()) {}
  double alpha() const { return fromCross(cross.norm()); }
  double alphaSigned(const Vec3& n) const { return fromCross(cross.dot(n)); }

 private:
  double fromCross(double c) const { return edgeSum > 0.0 ? 2.0 * std::sqrt(3.0) * c / edgeSum : 0.0; }
};

/// A quad's corner cross products e1_k x e2_k and edge sums |e1_k|^2 + |e2_k|^2 (see quadBeta), computed
/// once for its beta against several normals. beta() is quadBeta, betaWithNormal(n) quadBetaWithNormal.
struct QuadCorners {
  std::array<Vec3, 4> cross;
  std::array<double, 4> edgeSum;
  Vec3 diagonalNormal;  ///< (p2 - p0) x (p3 - p1), not normalised
  QuadCorners(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) : diagonalNormal((p2 - p0).cross(p3 - p1)) {
    const std::array<const Vec3*, 4> p{&p0, &p1, &p2, &p3};
    for (int k = 0; k < 4; ++k) {
      const Vec3 e1 = *p[(k + 1) % 4] - *p[k], e2 = *p[(k + 3) % 4] - *p[k];
      cross[k] = e1.cross(e2);
      edgeSum[k] = e1.squaredNorm() + e2.squaredNorm();
    }
  }
  double betaWithNormal(const Vec3& n) const {
    double sum = 0.0;
    for (int k = 0; k < 4; ++k) {
      const double ak = cross[k].dot(n);
      if (!(ak > 0.0)) return 0.0;
      sum += edgeSum[k] / ak;
    }
    if (!std::isfinite(sum) || !(sum > 0.0)) return 0.0;
    return 8.0 / sum;
  }
  double beta() const {
    const double len = diagonalNormal.norm();
    return len > 0.0 ? betaWithNormal(diagonalNormal / len) : 0.0;
  }
};

/// Summary of a set of quality values: min/mean/max and a histogram of `bins` equal bins on [0,1]
/// (values <= 0 fall in the first bin, values >= 1 in the last).
struct QualityStats {
  double min = 0, mean = 0, max = 0;
  std::size_t count = 0;
  std::size_t invalid = 0;  ///< values <= 0
  std::vector<std::size_t> histogram;
};
QualityStats summarizeQuality(const std::vector<double>& q, int bins = 10);

}  // namespace pectus
