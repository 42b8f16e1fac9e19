// Slice (intersection) method, thesis 6.3.1, with an automatic intrathoracic region and the bridging of
// slices that cut nothing (rules in the header).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/grid_cell.h"
#include "pectus/vol/thoracic_volume.h"

namespace pectus::vol {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kLargeGap = kPi / 3;  // gaps wider than 60 degrees (missing spine, abdominal opening): chord
inline double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }
}  // namespace

double SliceRegion::polygonArea() const {
  double a = 0;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0; i < n; ++i) a += cross2(polygon[i], polygon[(i + 1) % n]);
  return 0.5 * std::abs(a);
}

std::vector<std::vector<Seg2>> cutPlanes(const Soup& s, const std::vector<double>& zs) {
  std::vector<std::vector<Seg2>> out(zs.size());
  std::vector<std::size_t> order(zs.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return zs[a] < zs[b]; });
  std::vector<double> sorted(zs.size());
  for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = zs[order[i]];
  for (const auto& f : s.F) {
    const Eigen::Vector3d* p[3] = {&s.V[f[0]], &s.V[f[1]], &s.V[f[2]]};
    const double lo = std::min({p[0]->z(), p[1]->z(), p[2]->z()}), hi = std::max({p[0]->z(), p[1]->z(), p[2]->z()});
    auto it = std::lower_bound(sorted.begin(), sorted.end(), lo);
    for (; it != sorted.end() && *it <= hi; ++it) {
      const double z0 = *it;
      double d[3];
      for (int k = 0; k < 3; ++k) d[k] = p[k]->z() - z0;
      Eigen::Vector2d pts[2];
      int np = 0;
      for (int k = 0; k < 3 && np < 2; ++k) {
        const int l = (k + 1) % 3;
        if ((d[k] >= 0) != (d[l] >= 0)) {
          const double t = d[k] / (d[k] - d[l]);
          const Eigen::Vector3d q = *p[k] + t * (*p[l] - *p[k]);
          pts[np++] = q.head<2>();
        }
      }
      if (np == 2) out[order[std::size_t(it - sorted.begin())]].push_back({pts[0], pts[1]});
    }
  }
  return out;
}

namespace {
// least-squares slope dr/dk over up to 4 consecutive hit rays starting at k0 going in direction dir
double runSlope(const std::vector<double>& r, const std::vector<char>& hit, int k0, int dir) {
  const int K = int(r.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (int j = 0; j < 4; ++j) {
    const int k = ((k0 + dir * j) % K + K) % K;
    if (!hit[k]) break;
    const double x = dir * j;  // position relative to k0 in ray units (increasing angle)
    sx += x, sy += r[k], sxx += x * x, sxy += x * r[k], ++n;
  }
  if (n < 2) return std::nan("");
  const double den = n * sxx - sx * sx;
  return den > 0 ? (n * sxy - sx * sy) / den : std::nan("");
}
}  // namespace

namespace {
inline int wrapRay(int k, int K) { return ((k % K) + K) % K; }

// ray k's nearest crossing with the segments, seen from c: R.radius and R.hit for every ray, R.hits
void castRays(SliceRegion& R, const Eigen::Vector2d& c, int K) {
  const double dth = 2 * kPi / K;
  std::vector<double> best(K, 1e300);
  for (const auto& sg : R.segments) {
    const Eigen::Vector2d p = sg.a - c, q = sg.b - c, e = q - p;
    double a0 = std::atan2(p.y(), p.x()), a1 = std::atan2(q.y(), q.x());
    double da = a1 - a0;
    while (da > kPi) da -= 2 * kPi;
    while (da <= -kPi) da += 2 * kPi;
    double start = da >= 0 ? a0 : a1;
    const double span = std::abs(da);
    const long k0 = long(std::ceil(start / dth - 1e-12)), k1 = long(std::floor((start + span) / dth + 1e-12));
    for (long kk = k0; kk <= k1; ++kk) {
      const int k = int(((kk % K) + K) % K);
      const Eigen::Vector2d d(std::cos(k * dth), std::sin(k * dth));
      const double den = cross2(d, e);
      if (std::abs(den) < 1e-300) continue;
      const double t = cross2(p, e) / den, s = cross2(p, d) / den;
      if (t > 0 && s >= -1e-12 && s <= 1 + 1e-12 && t < best[k]) best[k] = t;
    }
  }
  for (int k = 0; k < K; ++k)
    if (best[k] < 1e299) R.hit[k] = 1, R.radius[k] = best[k], ++R.hits;
}

// the runs of consecutive hit rays as (first ray, length), in increasing angle from the first hit after a
// miss (there must be a miss and a hit)
std::vector<std::pair<int, int>> hitRuns(const std::vector<char>& hit) {
  const int K = int(hit.size());
  int s0 = 0;
  while (hit[s0] || !hit[wrapRay(s0 + 1, K)]) ++s0;  // s0: a miss followed by a hit
  std::vector<std::pair<int, int>> runs;
  for (int k = wrapRay(s0 + 1, K), n = 0; n < K;) {
    if (!hit[k]) { k = wrapRay(k + 1, K), ++n; continue; }
    int len = 0;
    while (hit[wrapRay(k + len, K)] && n + len < K) ++len;
    runs.push_back({k, len});
    k = wrapRay(k + len, K), n += len;
  }
  return runs;
}

// short runs of hits (under 3 degrees) that lie outward of the chord between the neighbouring runs
// are outer walls seen through a gap (parallax): dropped
void dropParallaxRuns(SliceRegion& R, int K) {
  auto at = [K](int k) { return wrapRay(k, K); };
  for (int pass = 0; pass < 5 && R.hits >= 3 && R.hits < K; ++pass) {
    bool changed = false;
    const std::vector<std::pair<int, int>> runs = hitRuns(R.hit);
    if (runs.size() < 3) break;
    const int maxLen = std::max(3, K / 120);
    for (std::size_t q = 0; q < runs.size(); ++q) {
      const auto [f, len] = runs[q];
      if (len > maxLen) continue;
      const auto& pr = runs[(q + runs.size() - 1) % runs.size()];
      const auto& nx = runs[(q + 1) % runs.size()];
      const int kp = at(pr.first + pr.second - 1), kn = nx.first;
      const int span = at(kn - kp);
      double excess = 0;
      for (int j = 0; j < len; ++j) {
        const double t = double(at(f + j - kp)) / span;
        const double chord = (1 - t) * R.radius[kp] + t * R.radius[kn];
        excess += (R.radius[at(f + j)] - chord) / chord;
      }
      if (excess / len > 0.01) {
        for (int j = 0; j < len; ++j) R.hit[at(f + j)] = 0, --R.hits;
        changed = true;
      }
    }
    if (!changed) break;
  }
}

// ends of the runs: walking from inside the run towards its end, the first ray that jumps outward of the
// linear extrapolation by more than 1 % starts the dropped tail (it sees the section's end face or an
// outer wall through the gap)
void dropJumpingRunEnds(SliceRegion& R, int K) {
  auto at = [K](int k) { return wrapRay(k, K); };
  for (const auto& [f, len] : hitRuns(R.hit)) {
    if (len < 6) continue;
    const int depth = std::min(len - 3, std::max(4, K / 60));
    for (int dir : {-1, +1}) {
      const int edge = dir > 0 ? at(f + len - 1) : f;
      for (int j = depth; j >= 0; --j) {
        const int e = at(edge - dir * j), i1 = at(e - dir), i2 = at(e - 2 * dir);
        if (!R.hit[e] || !R.hit[i1] || !R.hit[i2]) break;
        if (R.radius[e] - (2 * R.radius[i1] - R.radius[i2]) > 0.01 * R.radius[i1]) {
          for (int q = j; q >= 0; --q) {
            const int d = at(edge - dir * q);
            if (R.hit[d]) R.hit[d] = 0, --R.hits;
          }
          break;
        }
      }
    }
  }
}

// fills the gaps between hit rays (cubic Hermite in the angle, between the chord and the farther end; a
// straight chord across a large gap) and closes the polygon around c
void fillGaps(SliceRegion& R, const Eigen::Vector2d& c, int K) {
  const double dth = 2 * kPi / K;
  int first = 0;
  while (!R.hit[first]) ++first;
  int k = first;
  do {
    int next = (k + 1) % K;
    if (!R.hit[next]) {
      int g = 1;
      while (!R.hit[(k + g) % K]) ++g;
      const int k1 = (k + g) % K;
      const double r0 = R.radius[k], r1 = R.radius[k1];
      const double secant = (r1 - r0) / g;
      double m0 = runSlope(R.radius, R.hit, k, -1), m1 = runSlope(R.radius, R.hit, k1, +1);
      if (!std::isfinite(m0)) m0 = secant;
      if (!std::isfinite(m1)) m1 = secant;
      // the chord between the gap's end points, along each ray (a straight closure)
      const Eigen::Vector2d P0 = r0 * Eigen::Vector2d(std::cos(k * dth), std::sin(k * dth));
      const Eigen::Vector2d P1 = r1 * Eigen::Vector2d(std::cos(k1 * dth), std::sin(k1 * dth));
      const bool large = g * dth > kLargeGap;
      for (int j = 1; j < g; ++j) {
        const double th = (k + j) * dth;
        const Eigen::Vector2d d(std::cos(th), std::sin(th));
        const double den = cross2(d, P1 - P0);
        // (a gap of half a turn or more: the chord's line can be parallel to the ray or behind it; the
        // closure is kept between the centre and the farther end point, as a chord of a smaller gap is)
        const double chord = std::clamp(std::abs(den) > 1e-300 ? cross2(P0, P1 - P0) / den : std::min(r0, r1), 0.0,
                                        std::max(r0, r1));
        double r = chord;
        if (!large) {
          const double t = double(j) / g, t2 = t * t, t3 = t2 * t;
          const double h00 = 2 * t3 - 3 * t2 + 1, h01 = -2 * t3 + 3 * t2, h10 = t3 - 2 * t2 + t, h11 = t3 - t2;
          const double herm = h00 * r0 + h01 * r1 + (h10 * m0 + h11 * m1) * g;
          r = std::clamp(herm, chord, std::max({r0, r1, chord}));
        }
        R.radius[(k + j) % K] = std::max(r, 0.05 * std::min(r0, r1));
      }
      k = k1;
    } else {
      k = next;
    }
  } while (k != first);
  R.polygon.resize(K);
  for (int j = 0; j < K; ++j)
    R.polygon[j] = c + R.radius[j] * Eigen::Vector2d(std::cos(j * dth), std::sin(j * dth));
}
}  // namespace

SliceRegion regionFromSegments(double z, std::vector<Seg2> segments, int K, const std::optional<Eigen::Vector2d>& seed) {
  SliceRegion R;
  R.z = z;
  R.segments = std::move(segments);
  R.radius.assign(K, 0.0);
  R.hit.assign(K, 0);
  double len = 0;
  Eigen::Vector2d c(0, 0);
  for (const auto& sg : R.segments) {
    const double l = (sg.b - sg.a).norm();
    len += l, c += l * 0.5 * (sg.a + sg.b);
  }
  if (!(len > 0)) return R;
  c /= len;
  if (seed) c = *seed;
  R.centroid = c;
  castRays(R, c, K);
  if (R.hits < 3) return R;
  // rays that see an outer wall through a gap are treated as gaps: short runs outward of their
  // neighbours' chord, then the run ends that jump outward of the run's linear trend
  dropParallaxRuns(R, K);
  if (R.hits < 3) return R;
  if (R.hits < K) {
    dropJumpingRunEnds(R, K);
    if (R.hits < 3) return R;
  }
  fillGaps(R, c, K);
  return R;
}

namespace {
// pixel centres of the grid (origin o, pixel size h, cols x rows) inside the polygon (even-odd)
long long rasterCount(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& o, double h, int cols, int rows) {
  long long count = 0;
  std::vector<double> xs;
  double ylo = 1e300, yhi = -1e300;
  for (const auto& p : poly) ylo = std::min(ylo, p.y()), yhi = std::max(yhi, p.y());
  // rows and columns clamped to the grid in floating point before any cast: a polygon far outside the
  // grid (relative to the pixel size) would overflow int
  const int r0 = clampedCell((ylo - o.y()) / h - 0.5, rows), r1 = clampedCell(std::ceil((yhi - o.y()) / h), rows);
  const std::size_t n = poly.size();
  for (int r = r0; r <= r1; ++r) {
    const double y = o.y() + (r + 0.5) * h;
    xs.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const auto& p = poly[i];
      const auto& q = poly[(i + 1) % n];
      if ((p.y() > y) != (q.y() > y)) xs.push_back(p.x() + (y - p.y()) * (q.x() - p.x()) / (q.y() - p.y()));
    }
    std::sort(xs.begin(), xs.end());
    for (std::size_t i = 0; i + 1 < xs.size(); i += 2) {
      const double a = std::max(std::ceil((xs[i] - o.x()) / h - 0.5), 0.0);
      const double b = std::min(std::ceil((xs[i + 1] - o.x()) / h - 0.5) - 1, double(cols - 1));
      if (b >= a) count += static_cast<long long>(b - a) + 1;
    }
  }
  return count;
}
/// the slice method's parameters: throws InputError for a degenerate range or a parameter below its range
void checkSliceParams(const Range& range, const SliceParams& p) {
  requireRange(range, "of the slice method");
  if (!(p.spacing >= kSpacingRange.lo)) {
    std::ostringstream s;
    s << "the slice spacing must be at least " << kSpacingRange.lo << " mm";
    throw InputError(s.str());
  }
  if (p.resolution < kResolutionRange.lo)
    throw InputError("the raster resolution must be at least " + std::to_string(int(kResolutionRange.lo)) + " pixels");
  if (p.rays < kRaysRange.lo)
    throw InputError("the number of boundary rays must be at least " + std::to_string(int(kRaysRange.lo)));
}

/// The slices' regions and their polygons' areas (0 for an empty region). A region whose polygon has no
/// area (every ray stopped at the seed) counts as empty: it would set no extent (with only such regions the
/// pixel size would be 0 / resolution) and lie anywhere outside the raster.
struct SliceRegions {
  std::vector<SliceRegion> regions;
  std::vector<double> polyArea;
  bool hasArea(int k) const { return !regions[k].empty() && std::abs(polyArea[k]) > 0; }
};

/// the regions of the planes at heights z, cut from the soup
SliceRegions sliceRegions(const Soup& s, const std::vector<double>& z, int rays, const Progress& progress) {
  const int N = int(z.size());
  if (progress) progress(5, "cutting the planes");
  auto cuts = cutPlanes(s, z);
  SliceRegions R;
  R.regions.resize(N);
  R.polyArea.assign(N, 0.0);
  for (int k = 0; k < N; ++k) {
    R.regions[k] = regionFromSegments(z[k], std::move(cuts[k]), rays);
    if (!R.regions[k].empty()) R.polyArea[k] = R.regions[k].polygonArea();
    if (progress && k % std::max(1, N / 10) == 0) progress(10 + 60 * k / N, "slice regions");
  }
  return R;
}

/// the raster shared by the slices: pixel size px, cols x rows pixels from the origin o
struct SliceRaster {
  double px = 0;
  int cols = 0, rows = 0;
  Eigen::Vector2d o;
};

/// The raster over the common box of the regions with area, one pixel of margin on each side, resolution
/// pixels along its longer side. Throws InputError if no region has an area.
SliceRaster sliceRaster(const SliceRegions& R, const Range& range, int resolution) {
  const int N = int(R.regions.size());
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  int nonEmpty = 0;
  for (int k = 0; k < N; ++k) {
    if (!R.hasArea(k)) continue;
    ++nonEmpty;
    for (const auto& q : R.regions[k].polygon) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  }
  if (nonEmpty == 0) {
    std::ostringstream o;
    o << "no geometry in the measured range: none of the " << N << " planes between z = " << range.zLo << " and z = "
      << range.zHi << " mm cuts the layer in a section that encloses an area (check the range, the landmarks, or "
         "that the layer is the rib cage)";
    throw InputError(o.str());
  }
  SliceRaster G;
  const double ext = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  G.px = ext / resolution;
  const double px = G.px;
  G.cols = int(std::ceil((hi.x() - lo.x()) / px)) + 2;
  G.rows = int(std::ceil((hi.y() - lo.y()) / px)) + 2;
  G.o = lo - Eigen::Vector2d(px, px);
  return G;
}

/// Bridged slice k (a plane between two ribs, or through a missing or thin rib), between the slices with
/// area below and above: its rasterised area, and its polygon's area in polygonArea. Its region is
/// interpolated ray by ray: the boundary point on ray j moves linearly in z from the region below to the
/// region above (both regions have the same K ray angles, so the point is the interpolated centroid plus the
/// interpolated radius along the same direction: the bridged region is star-shaped like the others and lies
/// in the slices' common box). A wall running straight between the two cuts is reproduced exactly, and the
/// area follows the square of the interpolated radii, as a tapering section's area does (interpolating the
/// area itself would be linear in z). The region is rasterised like the measured ones, so the raster and
/// polygon volumes stay comparable.
double bridgedArea(const SliceRegions& R, const std::vector<double>& z, int k, int below, int above,
                   const SliceRaster& G, double& polygonArea) {
  const auto& P0 = R.regions[below].polygon;
  const auto& P1 = R.regions[above].polygon;
  const double t = (z[k] - z[below]) / (z[above] - z[below]);
  std::vector<Eigen::Vector2d> poly(P0.size());
  for (std::size_t j = 0; j < poly.size(); ++j) poly[j] = (1 - t) * P0[j] + t * P1[j];
  SliceRegion B;
  B.polygon = std::move(poly);
  polygonArea = B.polygonArea();
  return double(rasterCount(B.polygon, G.o, G.px, G.cols, G.rows)) * G.px * G.px;
}
}  // namespace

SliceResult sliceVolume(const Soup& s, const Range& range, const SliceParams& p, const Progress& progress) {
  checkSliceParams(range, p);
  SliceResult res;
  const int N = std::max(1, int(std::ceil((range.zHi - range.zLo) / p.spacing - 1e-9)));
  const double h = (range.zHi - range.zLo) / N;
  res.spacingUsed = h;
  res.slices = N;
  res.z.resize(N);
  for (int k = 0; k < N; ++k) res.z[k] = range.zLo + (k + 0.5) * h;
  const SliceRegions R = sliceRegions(s, res.z, p.rays, progress);
  const SliceRaster G = sliceRaster(R, range, p.resolution);
  res.pixel = G.px;
  const double px = G.px;
  res.area.assign(N, 0.0);
  res.bridged.assign(N, 0);
  int below = -1;  // the nearest slice with area below k
  for (int k = 0; k < N; ++k) {
    const auto& r = R.regions[k];
    if (!R.hasArea(k)) {
      ++res.emptySlices;
      int above = k + 1;
      while (above < N && !R.hasArea(above)) ++above;
      if (below < 0 || above >= N) {
        // beyond the last slice with area at either end of the range: nothing to interpolate, zero area
        ++res.endEmptySlices;
        continue;
      }
      double polygonArea = 0;
      ++res.bridgedSlices;
      res.bridged[k] = 1;
      res.area[k] = bridgedArea(R, res.z, k, below, above, G, polygonArea);
      res.volume += res.area[k] * h;
      res.polygonVolume += polygonArea * h;
      continue;
    }
    below = k;
    res.minCoverage = std::min(res.minCoverage, r.coverage());
    res.area[k] = double(rasterCount(r.polygon, G.o, px, G.cols, G.rows)) * px * px;
    res.volume += res.area[k] * h;
    res.polygonVolume += R.polyArea[k] * h;
    if (progress && k % std::max(1, N / 10) == 0) progress(70 + 30 * k / N, "rasterising");
  }
  return res;
}

}  // namespace pectus::vol
