#include "pectus/quality.h"

#include <algorithm>
#include <cmath>

namespace pectus {

double triangleAlpha(const Vec3& a, const Vec3& b, const Vec3& c) { return TriangleShape(a, b, c).alpha(); }

double triangleAlphaSigned(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  return TriangleShape(a, b, c).alphaSigned(n);
}

double quadBetaWithNormal(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, const Vec3& n) {
  return QuadCorners(p0, p1, p2, p3).betaWithNormal(n);
}

double quadBeta(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) { return QuadCorners(p0, p1, p2, p3).beta(); }

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
