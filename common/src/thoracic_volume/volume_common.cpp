#include <algorithm>
#include <cmath>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/labels.h"
#include "pectus/surface_cmesh.h"
#include "pectus/vol/thoracic_volume.h"

namespace pectus::vol {

Soup soupFromMesh(const CMeshO& m, const std::string& layer) {
  for (const auto& v : m.vert)
    if (!v.IsD() && !toEigen(v.cP()).allFinite())
      throw InputError("layer '" + layer + "' has NaN or infinite vertex coordinates; clean it first");
  // a vertebral column kept in a prepared cage is left out: the volume is the one inside the ribs, the same
  // whether the column was kept or cut away (labels.h, kVertebralColumn)
  const auto labels = readFaceLabels(m);
  SurfaceOf how;
  how.vertices = SurfaceOf::Vertices::All;
  if (labels) how.keepFace = [&](std::size_t i) { return labels->part[i] != kVertebralColumn; };
  return surfaceOf(m, how);
}

double divergenceVolume(const Soup& s) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (const auto& f : s.F)
    for (int k = 0; k < 3; ++k) c += s.V[f[k]], ++n;
  if (n) c /= double(n);
  double v = 0;
  for (const auto& f : s.F) v += (s.V[f[0]] - c).dot((s.V[f[1]] - c).cross(s.V[f[2]] - c));
  return v / 6.0;
}

void requireRange(const Range& r, const std::string& what) {
  if (!std::isfinite(r.zLo) || !std::isfinite(r.zHi))
    throw InputError("the measured range (" + what + ") is not finite");
  if (!(r.zHi - r.zLo > 1e-3)) {
    std::ostringstream o;
    o << "degenerate long axis: the measured range " << what << " runs from z = " << r.zLo << " to z = " << r.zHi
      << " mm; the upper end must lie above the lower end (check the landmarks or the given heights)";
    throw InputError(o.str());
  }
}

namespace {
struct Box {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  void add(const Eigen::Vector3d& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); }
  double diag() const { return (hi - lo).norm(); }
};
Box usedBox(const Soup& s, std::vector<char>& used) {
  used.assign(s.V.size(), 0);
  for (const auto& f : s.F)
    for (int k = 0; k < 3; ++k) used[f[k]] = 1;
  Box b;
  for (std::size_t i = 0; i < s.V.size(); ++i)
    if (used[i]) b.add(s.V[i]);
  return b;
}
}  // namespace

void requireComparablePair(const Soup& before, const Soup& after, const std::string& bn, const std::string& an) {
  std::vector<char> ub, ua;
  const Box bb = usedBox(before, ub), ba = usedBox(after, ua);
  std::size_t nb = std::count(ub.begin(), ub.end(), 1), na = std::count(ua.begin(), ua.end(), 1);
  if (before.V.size() != after.V.size() || nb != na) {
    std::ostringstream o;
    o << "the before layer '" << bn << "' (" << nb << " vertices) and the measured layer '" << an << "' (" << na
      << " vertices) are not the same model: a before/after comparison needs the deformed copy of the same mesh "
         "(e.g. the FE result of this cage)";
    throw InputError(o.str());
  }
  if (nb == 0) throw TopologyError("the before layer '" + bn + "' has no faces");
  const double db = bb.diag(), da = ba.diag();
  std::vector<double> disp;
  disp.reserve(nb);
  for (std::size_t i = 0; i < before.V.size(); ++i)
    if (ub[i]) disp.push_back((before.V[i] - after.V[i]).norm());
  std::nth_element(disp.begin(), disp.begin() + disp.size() / 2, disp.end());
  const double median = disp[disp.size() / 2];
  if (!(da > 0.8 * db && da < 1.25 * db) || median > 0.1 * db) {
    std::ostringstream o;
    o << "the before layer '" << bn << "' and the measured layer '" << an
      << "' are not in the same frame: bounding box diagonals " << db << " and " << da
      << " mm, median vertex displacement " << median
      << " mm (an FE correction moves the anterior wall only); bring both into the frame of labels.h (mm, +z "
         "superior) first";
    throw InputError(o.str());
  }
}

}  // namespace pectus::vol
