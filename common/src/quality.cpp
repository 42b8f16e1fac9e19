#include "pectus/quality.h"

#include <algorithm>
#include <cmath>

namespace pectus {

namespace {
const double kTwoSqrt3 = 2.0 * std::sqrt(3.0);

double alphaFromCross(double crossLen, const Vec3& a, const Vec3& b, const Vec3& c) {
  const double denom = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (!(denom > 0.0)) return 0.0;
  return kTwoSqrt3 * crossLen / denom;
}
}  // namespace

double triangleAlpha(const Vec3& a, const Vec3& b, const Vec3& c) {
  return alphaFromCross((b - a).cross(c - a).norm(), a, b, c);
}

double triangleAlphaSigned(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  return alphaFromCross((b - a).cross(c - a).dot(n), a, b, c);
}

double quadBetaWithNormal(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, const Vec3& n) {
  const std::array<const Vec3*, 4> p{&p0, &p1, &p2, &p3};
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    const Vec3 e1 = *p[(k + 1) % 4] - *p[k];
    const Vec3 e2 = *p[(k + 3) % 4] - *p[k];
    const double ak = e1.cross(e2).dot(n);
    if (!(ak > 0.0)) return 0.0;
    sum += (e1.squaredNorm() + e2.squaredNorm()) / ak;
  }
  if (!std::isfinite(sum) || !(sum > 0.0)) return 0.0;
  return 8.0 / sum;
}

double quadBeta(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  Vec3 n = (p2 - p0).cross(p3 - p1);
  const double len = n.norm();
  if (!(len > 0.0)) return 0.0;
  n /= len;
  return quadBetaWithNormal(p0, p1, p2, p3, n);
}

QualityStats summarizeQuality(const std::vector<double>& q, int bins) {
  QualityStats s;
  s.histogram.assign(static_cast<std::size_t>(std::max(bins, 1)), 0);
  if (q.empty()) return s;
  s.min = q.front();
  s.max = q.front();
  double sum = 0.0;
  for (double v : q) {
    s.min = std::min(s.min, v);
    s.max = std::max(s.max, v);
    sum += v;
    if (v <= 0.0) ++s.invalid;
    int b = static_cast<int>(std::floor(v * bins));
    b = std::clamp(b, 0, bins - 1);
    ++s.histogram[static_cast<std::size_t>(b)];
  }
  s.count = q.size();
  s.mean = sum / static_cast<double>(q.size());
  return s;
}

}  // namespace pectus
