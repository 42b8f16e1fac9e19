// Haller index and correction index measured on a slice of the model (the CT definitions applied
// to the cut of the rib cage by a horizontal plane):
//  transverse = widest inner extent in x of the intrathoracic region (rule of thoracic_volume.h);
//  apMin      = from the posterior surface of the sternum (the nearest section above the centroid on
//               the midline x = x_mid) to the anterior surface of the vertebra (landmark 503, else
//               the nearest section below the centroid on the midline, else the region's boundary);
//  apMax      = from the anterior-most inner margin of the chest wall (max y of the region) to the
//               vertebra; Haller = transverse / apMin, correction = (apMax - apMin) / apMax x 100 %.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/vol/thoracic_volume.h"

namespace pectus::vol {

namespace {
// y of the crossings of the vertical line x = x0 with the segments / the polygon
std::vector<double> crossings(const std::vector<Seg2>& segs, double x0) {
  std::vector<double> ys;
  for (const auto& s : segs) {
    if ((s.a.x() > x0) == (s.b.x() > x0)) continue;
    const double t = (x0 - s.a.x()) / (s.b.x() - s.a.x());
    ys.push_back(s.a.y() + t * (s.b.y() - s.a.y()));
  }
  return ys;
}
std::vector<double> polygonCrossings(const std::vector<Eigen::Vector2d>& poly, double x0) {
  std::vector<Seg2> segs;
  for (std::size_t i = 0; i < poly.size(); ++i) segs.push_back({poly[i], poly[(i + 1) % poly.size()]});
  return crossings(segs, x0);
}
}  // namespace

PectusIndex pectusIndexOnSlice(const SliceRegion& r, const std::optional<double>& midlineX,
                               const std::optional<double>& spineY) {
  if (r.empty()) {
    std::ostringstream o;
    o << "no geometry at the pectus index level z = " << r.z << " mm: the plane does not cut the rib cage";
    throw InputError(o.str());
  }
  // a section that encloses (next to) no area - a lone sheet, one triangle - has no chest to measure: its
  // region is a sliver around the seed (area under 1e-3 of the squared extent of the cut; a chest's is ~0.4)
  {
    Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
    for (const auto& sg : r.segments) lo = lo.cwiseMin(sg.a).cwiseMin(sg.b), hi = hi.cwiseMax(sg.a).cwiseMax(sg.b);
    const double ext = (hi - lo).maxCoeff();
    if (!(std::abs(r.polygonArea()) > 1e-3 * ext * ext))
      throw TopologyError("the pectus index cannot be measured at z = " + std::to_string(r.z) +
                       " mm: the section encloses no area (a sheet, not a chest)");
  }
  PectusIndex out;
  out.z = r.z;
  double xlo = 1e300, xhi = -1e300, ymax = -1e300;
  for (const auto& q : r.polygon) xlo = std::min(xlo, q.x()), xhi = std::max(xhi, q.x()), ymax = std::max(ymax, q.y());
  out.transverse = xhi - xlo;
  const double x0 = midlineX.value_or(r.centroid.x());
  const double cy = r.centroid.y();
  const auto segY = crossings(r.segments, x0), polyY = polygonCrossings(r.polygon, x0);
  double yS = 1e300, yV = -1e300;
  for (double y : segY)
    if (y > cy) yS = std::min(yS, y);
  if (yS < 1e299) out.sternumMeasured = true;
  else
    for (double y : polyY)
      if (y > cy) yS = std::min(yS, y);
  if (spineY) yV = *spineY, out.spineMeasured = true;
  else {
    for (double y : segY)
      if (y < cy) yV = std::max(yV, y);
    if (yV > -1e299) out.spineMeasured = true;
    else
      for (double y : polyY)
        if (y < cy) yV = std::max(yV, y);
  }
  if (!(yS < 1e299) || !(yV > -1e299) || !(yS > yV))
    throw InputError("the pectus index cannot be measured at z = " + std::to_string(r.z) +
                     " mm: the midline does not cross the sternum and the vertebra (check landmarks 501/503)");
  out.apMin = yS - yV;
  out.apMax = ymax - yV;
  out.haller = out.transverse / out.apMin;
  out.correction = 100.0 * (out.apMax - out.apMin) / out.apMax;
  return out;
}

// With the vertebra known: cast the rays from the midpoint between the vertebra and the first section
// above it on the midline (the sternum's posterior surface), which lies inside the chest however deep
// the funnel; the segments' centroid can fall in front of a deeply depressed sternum.
std::optional<Eigen::Vector2d> interiorSeed(const std::vector<Seg2>& segs, const IndexInputs& in) {
  if (!in.spineY || !in.midlineX) return std::nullopt;
  double yS = 1e300;
  for (double y : crossings(segs, *in.midlineX))
    if (y > *in.spineY + 1e-6) yS = std::min(yS, y);
  if (!(yS < 1e299)) return std::nullopt;
  // keep the segments' centroid (the slice rule's own seed) while it lies between vertebra and sternum
  double len = 0, cy = 0;
  for (const auto& sg : segs) {
    const double l = (sg.b - sg.a).norm();
    len += l, cy += l * 0.5 * (sg.a.y() + sg.b.y());
  }
  if (len > 0 && cy / len > *in.spineY && cy / len < yS) return std::nullopt;
  return Eigen::Vector2d(*in.midlineX, 0.5 * (*in.spineY + yS));
}

PectusIndex pectusIndex(const Soup& s, const IndexInputs& in) {
  if (in.level) {
    auto cuts = cutPlanes(s, {*in.level});
    const auto seed = interiorSeed(cuts[0], in);
    return pectusIndexOnSlice(regionFromSegments(*in.level, std::move(cuts[0]), in.rays, seed), in.midlineX, in.spineY);
  }
  // automatic: the deepest level = the slice of the range with the largest correction index
  requireRange(in.searchRange, "of the pectus index search");
  const int N = std::max(1, int(std::ceil((in.searchRange.zHi - in.searchRange.zLo) / in.searchSpacing)));
  std::vector<double> zs(N);
  for (int k = 0; k < N; ++k) zs[k] = in.searchRange.zLo + (k + 0.5) * (in.searchRange.zHi - in.searchRange.zLo) / N;
  auto cuts = cutPlanes(s, zs);
  std::optional<PectusIndex> best;
  for (int k = 0; k < N; ++k) {
    const auto seed = interiorSeed(cuts[k], in);
    const auto r = regionFromSegments(zs[k], std::move(cuts[k]), in.rays, seed);
    if (r.empty()) continue;
    try {
      const auto pi = pectusIndexOnSlice(r, in.midlineX, in.spineY);
      if (!best || pi.correction > best->correction) best = pi;
    } catch (const InputError&) {
    }
  }
  if (!best) throw InputError("no geometry in the pectus index search range: no slice crosses sternum and vertebra");
  return *best;
}

}  // namespace pectus::vol
